#!/usr/bin/python3
"""Which lens drops does the LED miss, and how much do they change the view? (issue 11;
docs/restoration_led.md, "Not done yet"). For each rain variant of the two quick suites: the drops of the
per-pixel majority truth (8-connected components of at least MIN_AREA px), each with its area, the
mean over its pixels of how much the lens alone changes the view (|targets/lens_only - clean|, the
largest of the three channels, 8-bit levels, averaged over the training views), the same for the
falling particles over it in one view (|images - targets/no_particles|, the mean over the views of its
per-view mean) and the peak of the averaged attention map `detect --save-attention` wrote. A drop
whose peak stays under MISSED_PEAK is under both shipped rules' levels (t 0.625, the peak rule's
seed 0.3).

Usage: restoration_led_faint.py MAPS
  MAPS/<paper|physical>_<pool|tanabata|factory>/attention/<view>.png from
  `weathergs detect --data data/suite_<suite>/<scene>_rain --out MAPS/<suite>_<scene> --save-attention`,
  run in the repository root (the datasets are read from data/suite_paper and data/suite_physical).
"""
import json
import os
import sys

import numpy as np
from PIL import Image
from scipy import ndimage

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from restoration_led_ensemble import read_attention  # noqa: E402
from restoration_led_ensemble import truths as read_truths  # noqa: E402  (the training views' lens masks)

MIN_AREA = 20  # px: smaller components are single pixels of the truth's 4-level edge, not drops
MISSED_PEAK = 0.3


def rgb(path):
    return np.asarray(Image.open(path).convert("RGB")).astype(np.float64)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    drops = []  # (area, mean change, particles' mean change, peak attention)
    for suite in ("paper", "physical"):
        for scene in ("pool", "tanabata", "factory"):
            ds, out = f"data/suite_{suite}/{scene}_rain", f"{sys.argv[1]}/{suite}_{scene}"
            views = json.load(open(os.path.join(ds, "dataset.json")))["splits"]["train"]
            attention = read_attention(out, ds)
            majority = read_truths(ds).mean(0) >= 0.5
            change = np.mean([np.abs(rgb(f"{ds}/targets/lens_only/{v}.png") - rgb(f"{ds}/clean/{v}.png")).max(-1)
                              for v in views], 0)
            particles = np.mean([np.abs(rgb(f"{ds}/images/{v}.png") - rgb(f"{ds}/targets/no_particles/{v}.png")).max(-1)
                                 for v in views], 0)
            labels, n = ndimage.label(majority, np.ones((3, 3)))
            for i in range(1, n + 1):
                m = labels == i
                if m.sum() >= MIN_AREA:
                    drops.append((m.sum(), change[m].mean(), particles[m].mean(), attention[m].max()))
                    print(f"{suite} {scene}_rain: drop of {m.sum()} px, change {change[m].mean():.1f} levels "
                          f"(particles {particles[m].mean():.1f}), peak attention {attention[m].max():.2f}")
    d = np.array(drops, float)
    missed = d[:, 3] < MISSED_PEAK
    print(f"\n{len(d)} drops of >= {MIN_AREA} px, {missed.sum()} missed (peak attention < {MISSED_PEAK})")
    for name, sel in (("missed", missed), ("found", ~missed)):
        q1, med, q3 = np.percentile(d[sel, 1], [25, 50, 75])
        print(f"{name}: area median {np.median(d[sel, 0]):.0f} px; mean change median {med:.1f} levels "
              f"(quartiles {q1:.1f}-{q3:.1f}); the particles over them {np.median(d[sel, 2]):.1f} levels")
    print(f"correlation of log(change) and peak attention: {np.corrcoef(np.log(d[:, 1]), d[:, 3])[0, 1]:.2f}")


if __name__ == "__main__":
    main()
