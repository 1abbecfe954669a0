#!/usr/bin/python3
"""Where the LED's masks lose against the cores ceiling (issue 11; docs/restoration_led_targets.md, "What
the post-processing allows"). For each rain variant of the two quick suites, the mask `weathergs detect`
wrote is scored (IoU / precision pooled over the training views, as detect scores it):
  - as it is;
  - with every missed drop of the majority truth (a component less than 30 % covered by the mask)
    added as its perfect core (the drop eroded and dilated three times);
  - then also without the mask's components that lie wholly further than 3 px from any view's drop;
against the ceiling: the majority mask's cores after the three dilations (restoration_led_ceiling.py).

Usage: restoration_led_gap.py MASKS
  MASKS/<paper|physical>_<pool|tanabata|factory>/ from
  `weathergs detect --data data/suite_<suite>/<scene>_rain --out MASKS/<suite>_<scene>`, run in the
  repository root (the datasets are read from data/suite_paper and data/suite_physical).
"""
import os
import sys

import numpy as np
from PIL import Image
from scipy import ndimage

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from restoration_led_ceiling import dilate, erode, score  # noqa: E402
from restoration_led_ensemble import truths as read_truths  # noqa: E402  (the training views' lens masks)

DILATIONS = 3
MISSED_RECALL = 0.3  # a truth drop less covered than this counts as missed
SQUARE = np.ones((3, 3), bool)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    for suite in ("paper", "physical"):
        for scene in ("pool", "tanabata", "factory"):
            ds, out = f"data/suite_{suite}/{scene}_rain", f"{sys.argv[1]}/{suite}_{scene}"
            truths = read_truths(ds)
            first = sorted(f for f in os.listdir(out) if f.endswith(".png"))[0]
            mask = np.asarray(Image.open(f"{out}/{first}").convert("L")) > 127  # one averaged mask for every view
            majority = truths.mean(axis=0) >= 0.5
            cores = dilate(erode(majority, DILATIONS), DILATIONS)

            labels, n = ndimage.label(majority, structure=SQUARE)
            missed, missed_areas = np.zeros_like(majority), []
            for k in range(1, n + 1):
                drop = labels == k
                if (mask & drop).sum() < MISSED_RECALL * drop.sum():
                    missed |= drop
                    missed_areas.append(int(drop.sum()))
            found = mask | (cores & missed)

            near = dilate(truths.any(axis=0), 3)
            mlabels, m = ndimage.label(mask, structure=SQUARE)
            far = np.zeros_like(mask)
            for k in range(1, m + 1):
                part = mlabels == k
                if not (part & near).any():
                    far |= part
            clean = found & ~far

            cells = [("shipped", mask), ("misses found as cores", found),
                     (f"and {int(far.sum())} far false px removed", clean), ("ceiling", cores)]
            print(f"{suite} {scene}_rain: {n} majority drops, {len(missed_areas)} missed (areas {sorted(missed_areas)})")
            print("  " + " | ".join(f"{name} {score(truths, mk)[0]:.3f} / {score(truths, mk)[1]:.3f}" for name, mk in cells))


if __name__ == "__main__":
    main()
