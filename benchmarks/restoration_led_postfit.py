#!/usr/bin/python3
"""Can a learned per-pixel post-processing of the averaged LED map find the drops better? (issue 11)

A logistic model per pixel over the averaged attention map a (what `detect --save-attention` writes)
and, optionally, full-resolution cues pooled over the dataset's training views that the network
never sees at that resolution: the mean |Laplacian| of the luminance (a lens-fixed drop blurs the same
place in every view), the per-pixel standard deviation over the views, and the gradient of the mean
view against the mean of the views' gradients (edges that stay put). Each cue enters alone and times
a, so it can move the map's boundary. Target: the per-pixel majority of the training views' truth,
eroded three times (the core that the three 3x3 dilations grow back; docs/restoration_led_targets.md,
"What the post-processing allows"). The probability threshold is chosen for the mean IoU after the three
dilations, like `calibrate-led`.

Scored two ways: cross-fitted on the held-out datasets (two fixed halves: fit and threshold on one,
score the other, and the reverse; the shipped rules are calibrated the same way for a fair baseline),
then fitted on all held-out datasets and scored on the benchmark (IoU / precision pooled over the
training views, as detect.json's `ground_truth`).

Usage:
  restoration_led_postfit.py --weathergs BIN --work DIR --weights STEM --held-out DATASET...
                             --benchmark DATASET...
Results: docs/restoration_led_record.md ("A learned post-processing of the averaged map").
"""
import argparse
import json
import os
import sys

import numpy as np
from PIL import Image
from scipy import ndimage, optimize

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from restoration_led_ceiling import dilate, erode, score  # noqa: E402  pooled IoU / precision, 3x3 squares
from restoration_led_ensemble import DILATIONS, PEAK_GRID, T_GRID, detect, rule_peak, rule_t, truths  # noqa: E402

CORE_EROSIONS = 3
PROBABILITY_GRID = np.arange(0.1, 0.9, 0.025)
SAMPLES = 400_000  # pixels drawn (seed 0) to fit the model: ~3 % of the held-out set
RIDGE = 1e-4       # on the standardized weights: keeps the fit finite where cues are collinear
FEATURE_SETS = {
    "map": [],
    "map shape": ["a_blur", "a_max9", "a_peak"],
    "image cues": ["sharp3", "sharp7", "sharp15", "std", "mean_grad", "consistent_grad"],
    "shape + image": ["a_blur", "a_max9", "a_peak", "sharp3", "sharp7", "sharp15", "std", "mean_grad",
                      "consistent_grad"],
}


def luminance(path):
    rgb = np.asarray(Image.open(path).convert("RGB")).astype(np.float64) / 255
    return rgb @ np.array([0.2126, 0.7152, 0.0722])


def log_ratio(x):
    """log of x against its median over the image: the cues' scale differs between scenes."""
    return np.log(x + 1e-4) - np.log(np.median(x) + 1e-4)


def features(a, dataset):
    views = json.load(open(os.path.join(dataset, "dataset.json")))["splits"]["train"]
    lum = np.stack([luminance(os.path.join(dataset, "images", v + ".png")) for v in views])
    f = {"a": a, "a_blur": ndimage.gaussian_filter(a, 2), "a_max9": ndimage.maximum_filter(a, 9)}
    labels, n = ndimage.label(a >= 0.2, structure=np.ones((3, 3)))
    peaks = ndimage.maximum(a, labels, index=np.arange(1, n + 1)) if n else np.zeros(0)
    f["a_peak"] = np.concatenate([[0.0], peaks])[labels]
    lap = np.abs(np.stack([ndimage.laplace(l) for l in lum])).mean(0)
    for k in (3, 7, 15):
        f[f"sharp{k}"] = log_ratio(ndimage.uniform_filter(lap, k))
    f["std"] = log_ratio(ndimage.uniform_filter(lum.std(0), 5))
    mean = lum.mean(0)
    grad_of_mean = ndimage.uniform_filter(np.hypot(ndimage.sobel(mean, 0), ndimage.sobel(mean, 1)), 5)
    mean_of_grads = ndimage.uniform_filter(np.mean([np.hypot(ndimage.sobel(l, 0), ndimage.sobel(l, 1)) for l in lum], 0), 5)
    f["mean_grad"] = log_ratio(grad_of_mean)
    f["consistent_grad"] = grad_of_mean / (mean_of_grads + 1e-4)
    return f


def design(f, keys):
    cols = [f["a"].ravel()] + [f[k].ravel() for k in keys] + [f["a"].ravel() * f[k].ravel() for k in keys]
    return np.stack(cols, 1)


def core_target(truth):
    return erode(truth.mean(0) > 0.5, CORE_EROSIONS).ravel().astype(np.float64)


def fit(items, keys):
    """items: (features, truth) pairs. Returns pixel probability as a function of features."""
    x = np.concatenate([design(f, keys) for f, _ in items])
    y = np.concatenate([core_target(t) for _, t in items])
    pick = np.random.default_rng(0).choice(len(y), min(len(y), SAMPLES), replace=False)
    x, y = x[pick], y[pick]
    mu, sd = x.mean(0), x.std(0) + 1e-9
    xn = np.concatenate([(x - mu) / sd, np.ones((len(y), 1))], 1)

    def loss(w):
        z = xn @ w
        reg = np.r_[w[:-1], 0.0]
        return (np.logaddexp(0, z) - y * z).mean() + RIDGE * reg @ reg, xn.T @ (1 / (1 + np.exp(-z)) - y) / len(y) + 2 * RIDGE * reg

    w = optimize.minimize(loss, np.zeros(xn.shape[1]), jac=True, method="L-BFGS-B").x
    return lambda f: (1 / (1 + np.exp(-(((design(f, keys) - mu) / sd) @ w[:-1] + w[-1])))).reshape(f["a"].shape)


def mean_iou(items, masks):
    return float(np.mean([score(t, dilate(m, DILATIONS))[0] for (_, t), m in zip(items, masks)]))


def calibrate(items, rule_grid, rule):
    """The grid point with the best mean IoU on items (rule(a or probability, point) -> mask)."""
    return max(rule_grid, key=lambda g: mean_iou(items, [rule(f, g) for f, _ in items]))


def learned_rule(train, keys):
    model = fit(train, keys)
    t = calibrate(train, PROBABILITY_GRID, lambda f, t: model(f) >= t)
    return lambda f: model(f) >= t


def shipped_rules(train):
    t = calibrate(train, T_GRID, lambda f, t: rule_t(f["a"], t))
    peak = calibrate(train, PEAK_GRID, lambda f, g: rule_peak(f["a"], *g))
    return {"t": lambda f: rule_t(f["a"], t), "peak": lambda f: rule_peak(f["a"], *peak)}


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--weathergs", required=True)
    p.add_argument("--work", required=True)
    p.add_argument("--weights", required=True, help="LED weights stem (the shipped: models/led/led)")
    p.add_argument("--held-out", nargs="+", required=True)
    p.add_argument("--benchmark", nargs="+", required=True)
    args = p.parse_args()

    def load(d):
        return features(detect(args, args.weights, d)[0], d), truths(d)

    held = [x for x in (load(d) for d in args.held_out) if x[1].any()]
    bench = [(d, load(d)) for d in args.benchmark]
    half = np.random.default_rng(1).permutation(len(held))
    folds = [[held[i] for i in half[: len(held) // 2]], [held[i] for i in half[len(held) // 2:]]]
    print(f"held-out datasets with drops: {len(held)} (cross-fitted in halves of {len(folds[0])} and {len(folds[1])})")
    candidates = {f"shipped {k}": (lambda train, k=k: shipped_rules(train)[k]) for k in ("t", "peak")}
    candidates.update({f"learned: {name}": (lambda train, keys=keys: learned_rule(train, keys))
                       for name, keys in FEATURE_SETS.items()})
    for name, make in candidates.items():
        crossed = []
        for train, test in ((folds[0], folds[1]), (folds[1], folds[0])):
            rule = make(train)
            crossed += [score(t, dilate(rule(f), DILATIONS)) for f, t in test]
        rule = make(held)
        cells = []
        for d, (f, t) in bench:
            iou, precision = score(t, dilate(rule(f), DILATIONS))
            cells.append(f"{os.path.basename(os.path.dirname(d.rstrip('/')))}/{os.path.basename(d.rstrip('/'))} "
                         f"{iou:.3f} / {precision:.3f}")
        print(f"{name}: held-out cross-fitted IoU {np.mean([c[0] for c in crossed]):.3f} "
              f"P {np.mean([c[1] for c in crossed]):.3f}; benchmark " + "; ".join(cells), flush=True)


if __name__ == "__main__":
    main()
