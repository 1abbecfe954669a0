#!/usr/bin/python3
"""The LED trained on the drops' cores instead of the whole drops (issue 11; docs/restoration_led_record.md,
"Trained on the drops' cores").

After the three 3x3 dilations the best mask a detector can write is each drop's core (the drop eroded
three times): benchmarks/restoration_led_ceiling.py. This trains the network on exactly that target.

  restoration_led_core_targets.py mirror E OUT DATASET...
      OUT/<name>/ for every DATASET: everything linked except masks/lens/, which holds the truth
      eroded E times by a 3x3 square (pixels outside the image count as drop). Train on the mirrors
      with the shipped recipe (the held-out market datasets stay the originals, so t and the peak
      rule are calibrated against the real drops):
        weathergs --threads 1 train-led --data OUT/* --held-out data/training_v3/market*_w* \\
            --out STEM --iterations 6000 --width 216 --seed 1 --threads 1 --calibrate-peak
  restoration_led_core_targets.py calibrate WORK STEM...
      For each weights STEM: t and the peak rule calibrated on held-out market (mean IoU after three
      dilations, as calibrate-led) on a grid wider than calibrate-led's (t 0.025..0.95; peak low
      0.05..0.6, seed low..0.7, fraction 0.3..0.9, steps 0.05: a core-trained network's maps are
      lower), then both rules scored on the two quick suites' rain and snow variants. Detections are
      cached under WORK. Run in the repository root with build/apps/weathergs built.
"""
import glob
import os
import sys
import types

import numpy as np
from PIL import Image

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import restoration_led_ensemble as ensemble  # noqa: E402  (detect, truths, rule_t, rule_peak)
from restoration_led_ceiling import dilate, erode, score  # noqa: E402

DILATIONS = 3
T_GRID = np.arange(0.025, 0.9501, 0.025)
PEAK_GRID = [(lo, seed, fr) for lo in np.arange(0.05, 0.601, 0.05) for seed in np.arange(lo, 0.701, 0.05)
             for fr in np.arange(0.3, 0.901, 0.05)]


def mirror(erosions, out_root, datasets):
    for ds in datasets:
        dst = os.path.join(out_root, os.path.basename(ds.rstrip("/")))
        os.makedirs(dst, exist_ok=True)
        for entry in os.listdir(ds):
            if entry != "masks" and not os.path.lexists(os.path.join(dst, entry)):
                os.symlink(os.path.abspath(os.path.join(ds, entry)), os.path.join(dst, entry))
        masks = os.path.join(ds, "masks")
        if not os.path.isdir(masks):
            continue
        for sub in os.listdir(masks):
            target = os.path.join(dst, "masks", sub)
            os.makedirs(os.path.dirname(target), exist_ok=True)
            if sub != "lens":
                if not os.path.lexists(target):
                    os.symlink(os.path.abspath(os.path.join(masks, sub)), target)
                continue
            os.makedirs(target, exist_ok=True)
            for f in os.listdir(os.path.join(masks, "lens")):
                m = np.asarray(Image.open(os.path.join(masks, "lens", f)).convert("L")) > 127
                Image.fromarray((erode(m, erosions) * 255).astype(np.uint8)).save(os.path.join(target, f))


def calibrate(work, stems):
    args = types.SimpleNamespace(weathergs="build/apps/weathergs", work=work)
    held_out = sorted(glob.glob("data/training_v3/market*_w*"))
    bench = [f"data/suite_{s}/{v}_{w}" for s in ("paper", "physical") for w in ("rain", "snow")
             for v in ("pool", "tanabata", "factory")]
    held = {d: ensemble.truths(d) for d in held_out}
    with_drops = [d for d in held_out if held[d].any()]
    truth = {d: ensemble.truths(d) for d in bench}
    for stem in stems:
        maps = {d: ensemble.detect(args, stem, d)[0] for d in held_out}

        def held_iou(rule):
            return float(np.mean([score(held[d], dilate(rule(maps[d]), DILATIONS))[0] for d in with_drops]))

        t_scores = {t: held_iou(lambda a, t=t: ensemble.rule_t(a, t)) for t in T_GRID}
        t = max(t_scores, key=t_scores.get)
        peak_scores = {g: held_iou(lambda a, g=g: ensemble.rule_peak(a, *g)) for g in PEAK_GRID}
        peak = max(peak_scores, key=peak_scores.get)
        print(f"{stem}: held-out IoU t {t:.3f}: {t_scores[t]:.4f}; peak "
              f"{tuple(round(float(x), 2) for x in peak)}: {peak_scores[peak]:.4f}")
        for name, rule in (("t", lambda a: ensemble.rule_t(a, t)), ("peak", lambda a: ensemble.rule_peak(a, *peak))):
            cells = [ensemble.cell(d.replace("data/suite_", ""), truth[d],
                                   dilate(rule(ensemble.detect(args, stem, d)[0]), DILATIONS)) for d in bench]
            print(f"  {name}: " + "; ".join(cells))
        sys.stdout.flush()


def main():
    if len(sys.argv) >= 5 and sys.argv[1] == "mirror":
        mirror(int(sys.argv[2]), sys.argv[3], sys.argv[4:])
    elif len(sys.argv) >= 4 and sys.argv[1] == "calibrate":
        calibrate(sys.argv[2], sys.argv[3:])
    else:
        sys.exit(__doc__)


if __name__ == "__main__":
    main()
