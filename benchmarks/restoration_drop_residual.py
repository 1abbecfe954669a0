#!/usr/bin/python3
"""Classical lens-drop baseline of issue 11: the residual of a 3DGS run, averaged over the training views
and thresholded (drops fixed to the lens cannot be fitted by 3D geometry), scored against the generator's
lens masks like `weathergs detect` (IoU / precision / recall of one mask for every view).

Usage: restoration_drop_residual.py SUITE_DIR RENDERS_DIR [VARIANT ...]
  SUITE_DIR:   a generated suite (data/suite_paper: images/, masks/lens/ per variant)
  RENDERS_DIR: RENDERS_DIR/<variant>/<view>.png, the training views rendered from a 3DGS model trained
               on the weathered images, e.g.
               weathergs render --model RUNS/<variant>/3dgs/seed0/model --split train --out RENDERS_DIR/<variant>
Thresholds tried: Otsu, the 80th and 85th percentile, mean + 1 and 1.5 standard deviations; each with no
dilation and with the LED's 3x3 dilation x3. Results: docs/restoration_led_record.md ("Classical drop baseline").
"""
import glob
import os
import sys

import numpy as np
from PIL import Image
from scipy import ndimage

DEFAULT_VARIANTS = ["tanabata_rain", "factory_rain", "pool_rain"]


def load(path):
    return np.asarray(Image.open(path).convert("RGB")).astype(np.float64) / 255


def otsu(values):
    hist, edges = np.histogram(values, 256)
    centers = (edges[:-1] + edges[1:]) / 2
    w0 = np.cumsum(hist)
    w1 = w0[-1] - w0
    m0 = np.cumsum(hist * centers) / np.maximum(w0, 1)
    m1 = (np.sum(hist * centers) - np.cumsum(hist * centers)) / np.maximum(w1, 1)
    return centers[np.argmax(w0 * w1 * (m0 - m1) ** 2)]


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    suite, renders = sys.argv[1], sys.argv[2]
    variants = sys.argv[3:] or DEFAULT_VARIANTS
    print("| variant | threshold | dilation | IoU | precision | recall | masked |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for v in variants:
        views = sorted(os.path.basename(f)[:-4] for f in glob.glob(f"{renders}/{v}/*.png"))
        if not views:
            sys.exit(f"{renders}/{v}: no rendered training views")
        residual = np.mean([np.abs(load(f"{renders}/{v}/{w}.png") - load(f"{suite}/{v}/images/{w}.png")).mean(2)
                            for w in views], 0)
        # The ground truth over the same views, as `weathergs detect` scores it: drops on in most views.
        truth = np.mean([np.asarray(Image.open(f"{suite}/{v}/masks/lens/{w}.png")) > 127 for w in views], 0) > 0.5
        rules = [("otsu", otsu(residual)), ("p80", np.percentile(residual, 80)), ("p85", np.percentile(residual, 85)),
                 ("mean+1sd", residual.mean() + residual.std()), ("mean+1.5sd", residual.mean() + 1.5 * residual.std())]
        for name, t in rules:
            for dilation in (0, 3):
                m = residual >= t
                if dilation:
                    m = ndimage.binary_dilation(m, iterations=dilation)
                inter, union = (m & truth).sum(), (m | truth).sum()
                print(f"| {v} | {name} | {dilation} | {inter / union:.2f} | {inter / max(m.sum(), 1):.2f} | "
                      f"{inter / truth.sum():.2f} | {100 * m.mean():.0f}% |")


if __name__ == "__main__":
    main()
