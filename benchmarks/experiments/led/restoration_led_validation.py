#!/usr/bin/python3
"""Scores LED weights on the validation scenes station and village (docs/restoration_led.md, "Current
numbers"), and with --against compares two LED variants by the rule that chooses between them.

The validation scenes are no benchmark scene, and no network is trained on them, so they can choose between
LED variants without choosing on the benchmark. The rule `detect --adapt` cuts its maps with is calibrated
on them (`make adapted-led-rule`), so an --adapt reading here is in-sample for that rule. Make them once
(an OUT of their own):

    TRAINING_PART=validation scripts/make-training-data.sh build/apps/weathergs data/validation 12 quick

This script runs `weathergs detect --data D --weights W` (the default post-processing) on every dataset of
VALIDATION (<scene>_wNN) and prints IoU / precision / recall against masks/lens (as detect.json reports them)
per dataset, the means over the datasets with drops, per scene and over both, and the largest fraction of a
drop-free dataset's pixels masked. With --against W2 it scores W2 the same way and prints the mean paired
difference of the IoU (W minus W2) with its standard error, and the verdict of the choosing rule (fixed
before any reading, so that the reading cannot move it): the higher mean IoU wins, within --margin (0.005)
the incumbent (W2) stays.

With --adapt the first weights run as `detect --adapt` (docs/restoration_led.md, "Adapted to the scene"):
`--adapt --against models/led/led` compares the adapted LED with the same weights as they are.

Usage: restoration_led_validation.py WEATHERGS VALIDATION OUT [--weights W] [--adapt] [--against W2] [--margin 0.005]
  Masks go to OUT/<tag>/<dataset>/ (tag a, b). Run in the repository root (the default weights are
  read from there).
"""
import argparse
import glob
import json
import math
import os
import subprocess
import sys

import numpy as np


def score(weathergs, datasets, out, weights, adapt=False):
    """{dataset: (iou, precision, recall, gt_fraction, mask_fraction)} from detect.json."""
    rows = {}
    for d in datasets:
        name = os.path.basename(d)
        m = os.path.join(out, name)
        subprocess.run([weathergs, "--quiet", "detect", "--data", d, "--out", m]
                       + (["--weights", weights] if weights else []) + (["--adapt"] if adapt else []),
                       check=True, stdout=subprocess.DEVNULL)
        report = json.load(open(os.path.join(m, "detect.json")))
        g = report["ground_truth"]
        if g is None:  # no masks/lens: a drop-free dataset; only what was masked counts
            views = report["views"]
            rows[name] = (math.nan, math.nan, math.nan, 0.0, sum(v["mask_fraction"] for v in views) / len(views))
        else:
            rows[name] = (g["iou"], g["precision"], g["recall"], g["gt_fraction"], g["mask_fraction"])
    return rows


def summary(tag, rows):
    drops = {k: v for k, v in rows.items() if v[3] > 0}
    clear = {k: v for k, v in rows.items() if v[3] == 0}
    print(f"\n{tag}: {len(rows)} datasets, {len(drops)} with drops")
    print("| scene | datasets with drops | mean IoU | mean precision | mean recall |")
    print("|---|---:|---:|---:|---:|")
    for scene in sorted({k.rsplit("_w", 1)[0] for k in drops}) + ["all"]:
        r = np.array([v[:3] for k, v in drops.items() if scene == "all" or k.rsplit("_w", 1)[0] == scene])
        print(f"| {scene} | {len(r)} | {r[:, 0].mean():.3f} | {r[:, 1].mean():.3f} | {r[:, 2].mean():.3f} |")
    if clear:
        worst = max(clear.items(), key=lambda kv: kv[1][4])
        print(f"drop-free datasets: at most {100 * worst[1][4]:.2f} % of the pixels masked ({worst[0]})")
    return drops


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("weathergs")
    p.add_argument("validation", help="the validation set (TRAINING_PART=validation scripts/make-training-data.sh)")
    p.add_argument("out")
    p.add_argument("--weights", help="LED weights stem (default: the installed ones)")
    p.add_argument("--against", help="a second weights stem, the incumbent: prints the paired comparison")
    p.add_argument("--margin", type=float, default=0.005, help="IoU difference within which the incumbent stays")
    p.add_argument("--adapt", action="store_true",
                   help="run --weights with `detect --adapt` (adapted to each dataset); --against may name the same weights")
    args = p.parse_args()
    manifest = os.path.join(args.validation, "manifest.json")
    if not os.path.exists(manifest) or '"part": "validation"' not in open(manifest).read():
        sys.exit(f"{manifest}: not a validation set; make it with TRAINING_PART=validation "
                 "scripts/make-training-data.sh build/apps/weathergs DIR 12 quick")
    datasets = sorted(d for d in glob.glob(os.path.join(args.validation, "*_w[0-9][0-9]"))
                      if os.path.exists(os.path.join(d, "dataset.json")))
    if not datasets:
        sys.exit(f"{args.validation}: no <scene>_wNN datasets")
    a = score(args.weathergs, datasets, os.path.join(args.out, "a"), args.weights, args.adapt)
    b = score(args.weathergs, datasets, os.path.join(args.out, "b"), args.against) if args.against else {}
    print("| dataset | IoU / precision / recall (weights) |" + (" IoU / precision / recall (against) |" if b else ""))
    print("|---|---|" + ("---|" if b else ""))
    for name in sorted(a):
        cells = [f"{v[0]:.3f} / {v[1]:.3f} / {v[2]:.3f}" if v[3] > 0 else f"no drops: {100 * v[4]:.2f} % masked"
                 for v in ([a[name]] + ([b[name]] if b else []))]
        print(f"| {name} | " + " | ".join(cells) + " |")
    drops = summary("weights " + (args.weights or "installed") + (", adapted" if args.adapt else ""), a)
    if not b:
        return
    summary("against " + args.against, b)
    d = np.array([a[k][0] - b[k][0] for k in sorted(drops)])
    se = d.std(ddof=1) / math.sqrt(len(d)) if len(d) > 1 else float("nan")
    print(f"\nmean paired IoU difference (weights - against) over {len(d)} datasets with drops: "
          f"{d.mean():+.4f}, standard error {se:.4f}")
    if abs(d.mean()) <= args.margin:
        print(f"within the margin {args.margin}: the incumbent ({args.against}) stays")
    else:
        print("the higher mean IoU wins: " + ((args.weights or "installed") if d.mean() > 0 else args.against))


if __name__ == "__main__":
    main()
