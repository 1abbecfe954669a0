#!/usr/bin/python3
"""Does averaging the maps of several LED networks (an ensemble) find the lens drops better? (issue 11)

For each set of weights, `weathergs detect --save-attention` writes the map averaged over a dataset's
training views; the ensemble's map is the mean of those maps (the same as averaging the networks'
per-view maps first: the mean is linear). Its threshold rules are calibrated on the held-out
datasets exactly as `calibrate-led` does (the global t on 0.05..0.95 by 0.025, then the peak rule
on low 0.2..0.6 x seed low..0.7 x fraction 0.5..0.9; mean IoU over the held-out datasets that have
drops; three 3x3 dilations) and both are scored on the benchmark datasets (IoU / precision pooled
over the training views, as detect.json's `ground_truth`; drop-free variants: the masked fraction).

Usage:
  restoration_led_ensemble.py --weathergs BIN --work DIR --held-out DATASET... --benchmark DATASET...
                              --set NAME=STEM[+STEM...] [--set ...]
The first --set should be the shipped weights alone: for it the script also checks that its own
rules reproduce the IoU that `detect` reported (they must, or the comparison means nothing).
Results: docs/restoration_led_record.md ("An ensemble of LED networks").
"""
import argparse
import hashlib
import json
import os
import subprocess
import sys

import numpy as np
from PIL import Image
from scipy import ndimage

from restoration_led_ceiling import dilate, score  # pooled IoU / precision, 3x3 dilations

DILATIONS = 3
T_GRID = np.arange(0.05, 0.9501, 0.025)  # kThresholdGrid (restoration/led_training.h)
PEAK_GRID = [(lo, seed, frac) for lo in np.arange(0.2, 0.601, 0.1) for seed in np.arange(lo, 0.701, 0.1)
             for frac in np.arange(0.5, 0.901, 0.05)]


def detect(args, stem, dataset):
    """The averaged attention map of one weights file on one dataset (cached under --work)."""
    out = os.path.join(args.work, os.path.basename(stem) + "_" + hashlib.sha256(os.path.abspath(stem).encode()).hexdigest()[:8],
                       dataset.strip("/").replace("/", "__"))
    if not os.path.exists(os.path.join(out, "detect.json")):
        os.makedirs(os.path.dirname(out), exist_ok=True)
        subprocess.run([args.weathergs, "--quiet", "--threads", "2", "detect", "--data", dataset, "--out", out,
                        "--weights", stem, "--save-attention"], check=True, stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "detect.json")) as f:
        report = json.load(f)
    return read_attention(out, dataset), report


def read_attention(out, dataset):
    """The averaged attention map `detect --save-attention` wrote to OUT (16-bit PNG, value / 65535; one
    map for every view, so the first training view's)."""
    views = json.load(open(os.path.join(dataset, "dataset.json")))["splits"]["train"]
    return np.asarray(Image.open(os.path.join(out, "attention", views[0] + ".png"))).astype(np.float64) / 65535


def variant_name(dataset):
    """<suite>/<variant> of a dataset path, the row label of the benchmark tables."""
    path = os.path.abspath(dataset.rstrip("/"))
    return os.path.basename(os.path.dirname(path)) + "/" + os.path.basename(path)


def truths(dataset):
    """The training views' ground-truth lens masks (V x H x W); no mask file means no drop."""
    views = json.load(open(os.path.join(dataset, "dataset.json")))["splits"]["train"]
    out = []
    for v in views:
        path = os.path.join(dataset, "masks", "lens", v + ".png")
        if os.path.exists(path):
            out.append(np.asarray(Image.open(path).convert("L")) > 127)
        else:
            out.append(np.zeros(np.asarray(Image.open(os.path.join(dataset, "images", v + ".png"))).shape[:2], bool))
    return np.stack(out)


def cell(label, truth, mask):
    """One benchmark cell: IoU / precision where the variant has drops, else the share of pixels masked."""
    if truth.any():
        iou, precision = score(truth, mask)
        return f"{label}: {iou:.3f} / {precision:.3f}"
    return f"{label}: masked {mask.mean() * 100:.2f} %"


def rule_t(a, t):
    return a >= t


def rule_peak(a, low, seed, fraction):
    """detect's peak rule: each 8-connected region of a >= low whose maximum reaches seed keeps a >= max(low,
    fraction x its maximum)."""
    labels, n = ndimage.label(a >= low, structure=np.ones((3, 3)))
    if n == 0:
        return np.zeros_like(a, bool)
    peaks = ndimage.maximum(a, labels, index=np.arange(1, n + 1))
    level = np.concatenate([[2.0], np.where(peaks >= seed, np.maximum(low, fraction * peaks), 2.0)])
    return (labels > 0) & (a >= level[labels])


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--weathergs", required=True)
    p.add_argument("--work", required=True)
    p.add_argument("--held-out", nargs="+", required=True)
    p.add_argument("--benchmark", nargs="+", required=True)
    p.add_argument("--set", action="append", required=True, help="NAME=STEM[+STEM...]")
    args = p.parse_args()
    held = {d: truths(d) for d in args.held_out}
    held_with_drops = [d for d in args.held_out if held[d].any()]
    bench = {d: truths(d) for d in args.benchmark}
    for k, spec in enumerate(args.set):
        name, stems = spec.split("=", 1)
        stems = stems.split("+")

        def ensemble_map(d):
            return np.mean([detect(args, s, d)[0] for s in stems], axis=0)

        if k == 0 and len(stems) == 1:  # our rules must reproduce what detect reported
            for d in args.benchmark:
                a, report = detect(args, stems[0], d)
                gt, pr = report.get("ground_truth"), report.get("peak_rule")
                if gt and pr and report.get("rule") == "peak" and report.get("dilate_iterations") == DILATIONS:
                    iou, _ = score(bench[d], dilate(rule_peak(a, pr["low"], pr["seed"], pr["fraction"]), DILATIONS))
                    if abs(iou - gt["iou"]) > 2e-3:  # the 16-bit map quantization moves it by ~1e-4
                        sys.exit(f"{d}: this script's peak rule gives IoU {iou:.4f}, detect reported {gt['iou']:.4f}")
        maps = {d: ensemble_map(d) for d in args.held_out}

        def held_iou(rule):
            return float(np.mean([score(held[d], dilate(rule(maps[d]), DILATIONS))[0] for d in held_with_drops]))

        t = max(T_GRID, key=lambda t: held_iou(lambda a: rule_t(a, t)))
        peak_scores = {g: held_iou(lambda a, g=g: rule_peak(a, *g)) for g in PEAK_GRID}
        peak = max(peak_scores, key=peak_scores.get)
        print(f"{name} ({' + '.join(stems)}): held-out IoU t {t:.3f}: {held_iou(lambda a: rule_t(a, t)):.3f}; "
              f"peak {tuple(round(float(x), 2) for x in peak)}: {peak_scores[peak]:.3f}")
        for rule_name, rule in (("t", lambda a: rule_t(a, t)), ("peak", lambda a: rule_peak(a, *peak))):
            cells = [cell(d, bench[d], dilate(rule(ensemble_map(d)), DILATIONS)) for d in args.benchmark]
            print(f"  {rule_name}: " + "; ".join(cells))


if __name__ == "__main__":
    main()
