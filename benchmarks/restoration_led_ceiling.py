#!/usr/bin/python3
"""The best lens-drop mask scores any detector can reach under the LED's post-processing (issue 11):
the ground truth itself, put through the same steps, scored as `weathergs detect` scores its masks
(IoU / precision pooled over the training views, restoration/detect_dataset.cc).

- `majority`: one mask for every view (the `train-views` averaging): the per-pixel majority of the
  training views' truths, the single mask with the most agreement;
- `per-view`: each view's own truth (the `--per-view` mode with a perfect network).
Each with 0..3 dilations by a 3x3 square (the released code's post-processing is 3).

The dilations only fix the *ground truth* as a detector; a detector that marks each drop's core and
lets the dilations grow it back does better. So each mask is also scored as `cores`: eroded n times
by the same square (pixels at the image border count as inside), then dilated n times, i.e. the
mask a perfect core detector would write after n dilations (a morphological opening, which keeps
every drop wider than 2n + 1 px at its shape). With 3 dilations this is the relevant ceiling.

Usage: restoration_led_ceiling.py DATASET [DATASET ...]   (generated datasets with masks/lens/)
Results: docs/restoration_led_targets.md ("What the post-processing allows").
"""
import json
import sys

import numpy as np
from PIL import Image
from scipy import ndimage

MAX_DILATIONS = 3


def score(truths, mask):
    """Pooled IoU and precision of one mask (H x W) or one per view (V x H x W) against V truths."""
    mask = np.broadcast_to(mask, truths.shape)
    inter = np.count_nonzero(truths & mask)
    union = np.count_nonzero(truths | mask)
    pred = np.count_nonzero(mask)
    return (inter / union if union else 1.0), (inter / pred if pred else 1.0)


def dilate(mask, n):
    if n == 0:
        return mask
    square = np.ones((3, 3), bool)
    if mask.ndim == 2:
        return ndimage.binary_dilation(mask, square, iterations=n)
    return np.stack([ndimage.binary_dilation(m, square, iterations=n) for m in mask])


def erode(mask, n):
    if n == 0:
        return mask
    square = np.ones((3, 3), bool)
    if mask.ndim == 2:
        return ndimage.binary_erosion(mask, square, iterations=n, border_value=1)
    return np.stack([ndimage.binary_erosion(m, square, iterations=n, border_value=1) for m in mask])


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for ds in sys.argv[1:]:
        try:
            with open(f"{ds}/dataset.json") as f:
                views = json.load(f)["splits"]["train"]
            truths = np.stack([np.asarray(Image.open(f"{ds}/masks/lens/{v}.png").convert("L")) > 127 for v in views])
        except (OSError, KeyError, ValueError) as e:
            sys.exit(f"{ds}: not a generated dataset with masks/lens/ and a train split ({e})")
        majority = truths.mean(axis=0) >= 0.5
        print(f"{ds}: drops on {truths.mean() * 100:.1f}% of the training pixels")
        for name, mask in (("majority", majority), ("per-view", truths)):
            for cores in (False, True):
                cells = []
                for n in range(MAX_DILATIONS + 1):
                    iou, precision = score(truths, dilate(erode(mask, n) if cores else mask, n))
                    cells.append(f"{n} dil: IoU {iou:.3f} P {precision:.3f}")
                label = name + (" cores" if cores else "")
                print(f"  {label:15s} " + " | ".join(cells))


if __name__ == "__main__":
    main()
