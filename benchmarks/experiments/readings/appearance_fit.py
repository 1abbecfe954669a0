#!/usr/bin/python3
"""GS-W renders a view in the appearance of a reference image; for a benchmark's test view the only
image there is is the weathered one. This scores a run's test renders twice against clean/: as
rendered (our gs-w-lite: the identity appearance), and after the affine colour transform that best
maps each render onto the weathered test image (least squares over the view's pixels: 12 numbers,
the form of gs-w-lite's own per-view appearance), i.e. the test views taken in the weather's
appearance, as GS-W conditioned on the weathered test image would render them.

Usage: appearance_fit.py WEATHERGS_BINARY DATASET RUN...   (prints one line per run: PSNR / SSIM /
LPIPS as rendered and with the fitted appearance; writes RUN/renders_weather_appearance/)
"""
import json
import os
import subprocess
import sys

import numpy as np
from PIL import Image


def load(path):
    return np.asarray(Image.open(path).convert("RGB"), dtype=np.float64) / 255.0


def evaluate(binary, data, renders, method, out):
    subprocess.run([binary, "--quiet", "evaluate", "--gt", data, "--renders", renders, "--method", method, "-o", out],
                   check=True, stdout=subprocess.DEVNULL)
    m = json.load(open(out))["metrics"]
    return m["psnr"], m["ssim"], m["lpips"]


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    binary, data = os.path.realpath(sys.argv[1]), os.path.realpath(sys.argv[2])
    views = json.load(open(os.path.join(data, "dataset.json")))["splits"]["test"]
    for run in map(os.path.realpath, sys.argv[3:]):
        renders = os.path.join(run, "renders", "test")
        if not os.path.isdir(renders):
            renders = os.path.join(run, "renders")
        fitted_dir = os.path.join(run, "renders_weather_appearance")
        os.makedirs(fitted_dir, exist_ok=True)
        for v in views:
            r = load(os.path.join(renders, v + ".png")).reshape(-1, 3)
            w = load(os.path.join(data, "images", v + ".png")).reshape(-1, 3)
            x = np.hstack([r, np.ones((len(r), 1))])
            coef, *_ = np.linalg.lstsq(x, w, rcond=None)  # 4 x 3: A^T stacked over b
            out = np.clip(x @ coef, 0, 1).reshape(load(os.path.join(renders, v + ".png")).shape)
            Image.fromarray(np.round(out * 255).astype(np.uint8)).save(os.path.join(fitted_dir, v + ".png"))
        name = os.path.basename(run)
        own = evaluate(binary, data, renders, name, os.path.join(run, "score_as_rendered.json"))
        fit = evaluate(binary, data, fitted_dir, name, os.path.join(run, "score_weather_appearance.json"))
        print(f"{run}: as rendered {own[0]:.2f} / {own[1]:.4f} / {own[2]:.4f}; "
              f"in the weathered test image's appearance {fit[0]:.2f} / {fit[1]:.4f} / {fit[2]:.4f}")


if __name__ == "__main__":
    main()
