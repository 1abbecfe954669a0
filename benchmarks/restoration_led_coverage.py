#!/usr/bin/python3
"""The LED's masks scored against where the drops are on the lens, not only where they show (issue 11;
docs/restoration_led_targets.md, "Where the drops are, not where they show").

masks/lens/ (the generator's default `perceptible` rule) counts a pixel where the drops change that
view's 8-bit image by more than 4 levels, so it moves from view to view with the scene behind a drop,
and one averaged mask cannot exceed IoU ~0.85 against it. The lens stage also writes the drops' blurred
coverage, layers/lens_coverage/<view>.exr, which for drops fixed to the lens is the same in every view;
its `coverage` rule (coverage >= 0.1, docs/lens_droplets.md) is what masks/lens/ holds when a spec asks
for `"mask_rule": "coverage"`. For each rain variant of the two suites this prints, pooled over the
training views as `weathergs detect` scores: the mask against masks/lens/ (IoU / precision), against
coverage >= THRESHOLD (IoU / precision / recall), and that truth's ceiling for one mask after the three
dilations (its per-pixel majority over the views, opened by three 3x3 erosions and dilations, as in
restoration_led_ceiling.py).

Usage: restoration_led_coverage.py MASKS [--threshold 0.1]
  MASKS/<paper|physical>_<pool|tanabata|factory>/ from
  `weathergs detect --data data/suite_<suite>/<scene>_rain --out MASKS/<suite>_<scene>`, run in the
  directory that holds data/ (the repository root, or the OUT of restoration_led_profile.sh). The
  datasets need their layers (generated without --no-layers).
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
from PIL import Image

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from restoration_led_ceiling import dilate, erode, score  # noqa: E402
from restoration_led_ensemble import truths as read_truths  # noqa: E402  (the training views' lens masks)

DILATIONS = 3


def coverage(dataset):
    """The training views' blurred lens coverage (V x H x W, [0, 1]), read through oiiotool (no EXR
    reader in Debian's Python): each layer written as a 16-bit PNG, so values are exact to 1/65535."""
    views = json.load(open(os.path.join(dataset, "dataset.json")))["splits"]["train"]
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        for v in views:
            exr = os.path.join(dataset, "layers", "lens_coverage", v + ".exr")
            if not os.path.exists(exr):
                sys.exit(f"{exr}: missing (generate the dataset with its layers, without --no-layers)")
            png = os.path.join(tmp, v + ".png")
            subprocess.run(["oiiotool", exr, "--ch", "0", "-d", "uint16", "-o", png], check=True)
            out.append(np.asarray(Image.open(png)).astype(np.float64) / 65535)
    return np.stack(out)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("masks")
    p.add_argument("--threshold", type=float, default=0.1, help="coverage rule: coverage at least this (0.1)")
    args = p.parse_args()
    print(f"| variant | vs masks/lens: IoU / precision | vs coverage >= {args.threshold:g}: IoU / precision / recall "
          "| coverage share of pixels | one-mask ceiling vs coverage: IoU / precision |")
    print("|---|---|---|---:|---|")
    for suite in ("paper", "physical"):
        for scene in ("pool", "tanabata", "factory"):
            ds, out = f"data/suite_{suite}/{scene}_rain", f"{args.masks}/{suite}_{scene}"
            if not os.path.isdir(out):
                continue
            first = sorted(f for f in os.listdir(out) if f.endswith(".png"))[0]
            mask = np.asarray(Image.open(f"{out}/{first}").convert("L")) > 127  # one averaged mask for every view
            perceptible = read_truths(ds)
            covered = coverage(ds) >= args.threshold
            cores = dilate(erode(covered.mean(axis=0) >= 0.5, DILATIONS), DILATIONS)
            pi, pp = score(perceptible, mask)
            ci, cp = score(covered, mask)
            recall = np.count_nonzero(covered & mask) / max(1, np.count_nonzero(covered))
            ki, kp = score(covered, cores)
            print(f"| {suite} {scene}_rain | {pi:.3f} / {pp:.3f} | {ci:.3f} / {cp:.3f} / {recall:.3f} "
                  f"| {covered.mean() * 100:.1f} % | {ki:.3f} / {kp:.3f} |")


if __name__ == "__main__":
    main()
