#!/usr/bin/python3
"""How much could any geometric multi-view cue tell the lens drops apart? An upper bound (issue 11;
docs/restoration_led_targets.md, "No multi-view cue: the oracle registration bound").

A drop fixed to the lens stays at the same pixel while the scene moves behind it, so every view that
sees a scene point outside a drop contradicts the view whose drop covers it. This script measures that
contradiction with the best registration there can be, the clean scene's own depth (an oracle no
method has): every pixel x of training view i is lifted with depth/<i>.exr, projected into every other
training view j, kept if j sees the same surface there (j's clean depth within 3 % + 5 cm) and if the
point moved by more than --min-shift px (else a drop would be compared with itself), and
r_ij(x) = max over channels |I_i(x) - I_j(x_j)| (8-bit levels, bilinear). R_i = the median over j
(robust to the streaks and drops of single views), R = the mean of R_i over the training views: a map
in lens coordinates, like the LED's averaged attention. Scored against the per-pixel majority of the
training views' masks/lens (the one-mask truth of restoration_led_ceiling.py):
- ROC AUC of R and of the LED's averaged map (`detect --save-attention`), and the best AUC of
  LED + w R / p99(R) over w (does R add to the network?);
- the best IoU / precision of R >= t after the three 3x3 dilations, t tuned on the variant itself
  (a bound, not a detector);
- per drop of the majority truth (>= 20 px): its area, the LED map's peak, and where its mean R ranks
  among the pixels away from every drop (1.0: above all of them).

Usage: restoration_led_registration.py [--source images|lens_only|no_particles] [--min-shift PX]
                                       DATASET:MAPS...
  DATASET a generated rain variant with depth/ and masks/lens/ (`weathergs generate ... --targets`
  for the other sources); MAPS the folder `weathergs detect --data DATASET --out MAPS
  --save-attention` wrote.
"""
import argparse
import json
import os
import subprocess
import tempfile

import numpy as np
from PIL import Image
from scipy import ndimage, stats

from restoration_led_ceiling import dilate, score
from restoration_led_ensemble import read_attention, truths, variant_name

MIN_DROP_AREA = 20        # px, as restoration_led_faint.py
DILATIONS = 3             # the released code's, as detect
VISIBLE_REL, VISIBLE_ABS = 0.03, 0.05  # same surface in view j: |depth_j - z_j| < 3 % of z_j + 5 cm
BACKGROUND_GAP = 4        # px: "away from every drop" = outside the majority truth dilated this often


def rgb(path):
    return np.asarray(Image.open(path).convert("RGB")).astype(np.float64)


def read_depth(path, tmp):
    """Planar depth (metres) of an EXR; background (>= 1e9 or not finite) as 1e4 m."""
    tif = os.path.join(tmp, "depth.tif")
    subprocess.run(["oiiotool", path, "--ch", "0", "-d", "float", "-o", tif], check=True)
    z = np.asarray(Image.open(tif)).astype(np.float64)
    return np.where(np.isfinite(z) & (z < 1e9), z, 1e4)


def bilinear(img, x, y):
    """img (H x W x C) at pixel coordinates x, y (pixel centres at +0.5), edge-clamped."""
    h, w = img.shape[:2]
    x = np.clip(x - 0.5, 0, w - 1.001)
    y = np.clip(y - 0.5, 0, h - 1.001)
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    top = img[y0, x0] * (1 - fx) + img[y0, x0 + 1] * fx
    bottom = img[y0 + 1, x0] * (1 - fx) + img[y0 + 1, x0 + 1] * fx
    return top * (1 - fy) + bottom * fy


def auc(s, label):
    """ROC AUC with tied scores ranked by their mean rank."""
    s, label = s.ravel(), label.ravel()
    ranks = stats.rankdata(s)
    npos, nneg = label.sum(), (~label).sum()
    return (ranks[label].sum() - npos * (npos + 1) / 2) / (npos * nneg)


def registration_residual(dataset, source, min_shift, tmp):
    """R (H x W), the median shift between view pairs, and the share of (view, pixel) with a valid R_i."""
    views = json.load(open(os.path.join(dataset, "dataset.json")))["splits"]["train"]
    cams = {c["name"]: c for c in json.load(open(os.path.join(dataset, "cameras.json")))["views"]}
    folder = "images" if source == "images" else os.path.join("targets", source)
    img = {v: rgb(os.path.join(dataset, folder, v + ".png")) for v in views}
    depth = {v: read_depth(os.path.join(dataset, "depth", v + ".exr"), tmp) for v in views}
    h, w = img[views[0]].shape[:2]
    xs, ys = np.meshgrid(np.arange(w) + 0.5, np.arange(h) + 0.5)
    per_view, shifts = [], []
    for i in views:
        ci, z = cams[i], depth[i]
        camera = np.stack([(xs - ci["cx"]) / ci["fx"] * z, (ys - ci["cy"]) / ci["fy"] * z, z, np.ones_like(z)], -1)
        world = camera @ np.linalg.inv(np.array(ci["camera_from_world"])).T
        residuals = []
        for j in views:
            if j == i:
                continue
            cj = cams[j]
            pj = world @ np.array(cj["camera_from_world"]).T
            zj = pj[..., 2]
            with np.errstate(divide="ignore", invalid="ignore"):
                u = cj["fx"] * pj[..., 0] / zj + cj["cx"]
                v = cj["fy"] * pj[..., 1] / zj + cj["cy"]
            inside = (zj > 0) & (u >= 0.5) & (u < w - 0.5) & (v >= 0.5) & (v < h - 0.5)
            u, v = np.where(inside, u, xs), np.where(inside, v, ys)
            visible = np.abs(bilinear(depth[j][..., None], u, v)[..., 0] - zj) < VISIBLE_REL * zj + VISIBLE_ABS
            shift = np.hypot(u - xs, v - ys)
            shifts.append(np.median(shift[inside]))
            r = np.abs(img[i] - bilinear(img[j], u, v)).max(-1)
            residuals.append(np.where(inside & visible & (shift > min_shift), r, np.nan))
        stack = np.stack(residuals)
        counts = np.isfinite(stack).sum(0)
        med = np.nanmedian(np.where(counts > 0, stack, 0), 0)  # all-NaN columns: 0, marked invalid below
        per_view.append(np.where(counts > 0, med, np.nan))
    per_view = np.stack(per_view)
    valid = np.isfinite(per_view)
    mean = np.where(valid.any(0), np.nansum(per_view, 0) / np.maximum(valid.sum(0), 1), 0.0)
    return mean, float(np.median(shifts)), float(valid.mean())


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--source", default="images", choices=["images", "lens_only", "no_particles"])
    p.add_argument("--min-shift", type=float, default=12.0, help="px a point must move between two views")
    p.add_argument("pairs", nargs="+", metavar="DATASET:MAPS")
    args = p.parse_args()
    print("| variant | median shift, px | valid | AUC: R / LED / best LED + w R | R >= t, tuned: IoU / precision | "
          "drops missed by the LED: R's rank among the background | found |")
    print("|---|---:|---:|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for pair in args.pairs:
            dataset, maps = pair.rsplit(":", 1)
            R, shift, valid = registration_residual(dataset, args.source, args.min_shift, tmp)
            attention = read_attention(maps, dataset)
            truth = truths(dataset)
            majority = truth.mean(0) >= 0.5
            scale = np.percentile(R, 99) or 1.0
            combined = max(auc(attention + wt * R / scale, majority) for wt in (0.05, 0.1, 0.2, 0.5, 1.0))
            best = max((score(truth, dilate(R >= t, DILATIONS)) for t in np.arange(2, 60.1, 1.0)), key=lambda s: s[0])
            labels, n = ndimage.label(majority, np.ones((3, 3)))
            background = R[~ndimage.binary_dilation(majority, iterations=BACKGROUND_GAP)]
            missed, found = [], []
            for k in range(1, n + 1):
                drop = labels == k
                if drop.sum() < MIN_DROP_AREA:
                    continue
                rank = (background < R[drop].mean()).mean()
                (missed if attention[drop].max() < 0.3 else found).append(rank)
            med = lambda x: f"{np.median(x):.2f} (n {len(x)})" if x else "none"
            print(f"| {variant_name(dataset)} | {shift:.1f} | {valid:.2f} | {auc(R, majority):.3f} / {auc(attention, majority):.3f} / "
                  f"{combined:.3f} | {best[0]:.3f} / {best[1]:.3f} | {med(missed)} | {med(found)} |", flush=True)


if __name__ == "__main__":
    main()
