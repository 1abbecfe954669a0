#!/usr/bin/python3
"""What each rain intensity of training.sh's rain-<intensity> cells and the AEF do to the images
(docs/record/readings.md, "The rain gain against the rain's intensity"): per intensity, the share of
the pixels the particle mask covers (all views), and over the training views the PSNR against clean/
of the weathered images and of the weathergs run's AEF output (filtered/), with image_level.py's
detail measure (1 = as sharp as the scene).

Usage: rain_images.py TUNING_DIR READINGS_DIR SCENE   (e.g. village; heavy is TUNING_DIR/<SCENE>_rain,
moderate and light are training.sh's READINGS_DIR/data/<SCENE>_rain_<intensity>)
"""
import json
import os
import sys

import numpy as np

from image_level import laplacian_variance, load


def psnr(a, b):
    return 10 * np.log10(1 / np.mean((a - b) ** 2))


def row(data, filtered):
    ds = json.load(open(os.path.join(data, "dataset.json")))
    views = ds["splits"]["train"]
    masks = os.path.join(data, "masks", "particles")
    cover = np.mean([np.mean(load(os.path.join(masks, f), gray=True) > 0.5) for f in sorted(os.listdir(masks))])
    clean = {v: load(os.path.join(data, "clean", v + ".png")) for v in views}
    out = {"particle_cover": float(cover)}
    for label, folder in (("weathered", os.path.join(data, "images")), ("aef", filtered)):
        imgs = {v: load(os.path.join(folder, v + ".png")) for v in views}
        out[label + "_psnr"] = float(np.mean([psnr(imgs[v], clean[v]) for v in views]))
        out[label + "_detail"] = float(np.mean([laplacian_variance(imgs[v]) / laplacian_variance(clean[v]) for v in views]))
    return out


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    tuning, readings, scene = sys.argv[1:]
    runs = os.path.join(readings, "runs", scene + "_rain")
    cases = [("heavy", os.path.join(tuning, scene + "_rain"), os.path.join(runs, "weathergs"))]
    cases += [(i, os.path.join(readings, "data", f"{scene}_rain_{i}"), os.path.join(runs, "rain-" + i, "weathergs"))
              for i in ("moderate", "light")]
    print("| rain | particle mask covers | PSNR vs clean: weathered / AEF output | detail: weathered / AEF output |")
    print("|---|---|---|---|")
    for intensity, data, run in cases:
        if not os.path.isdir(os.path.join(run, "filtered")):
            print(f"| {intensity} | – | – | – |")
            continue
        r = row(data, os.path.join(run, "filtered"))
        print(f"| {intensity} | {100 * r['particle_cover']:.1f}% | {r['weathered_psnr']:.2f} / {r['aef_psnr']:.2f} dB | "
              f"{r['weathered_detail']:.2f} / {r['aef_detail']:.2f} |")


if __name__ == "__main__":
    main()
