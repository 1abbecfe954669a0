#!/usr/bin/python3
"""What robust-3dgs's RobustFilter mask excludes at the end of training, against the true particles
(docs/record/robust_snow.md). Tuning scenes only, never the benchmark's.

For each RUN (a `weathergs reconstruct` folder) the training views are rendered from RUN/model, and the
rule of reconstruction/robust_mask.h is applied with the run's final threshold (the
"robust_threshold" of RUN/model/checkpoint.bin; a run without one, e.g. plain 3DGS, is scored with
--threshold-from's): per-pixel error e = mean |render - weathered image| over the channels, inlier
when e < tau, kept when an inlier or when more than half of its 3x3 neighbourhood is. The warm-up's
random keeps are spent by then (keep probability exp(-3e-3 x floor(iteration / 1.5)) < 1e-6 after
~7000 iterations), so this is the mask the last iterations trained with, up to the running histogram
(the last ~20 views, not the last view alone).

Printed per run: its test scores (RUN/results.json) and its curve (RUN/curve.json: test PSNR at each
scored iteration); then, over the training views (a Markdown table):
- excluded: the share of pixels the mask excludes;
- weather share: the share of pixels the weather covers (masks/particles, with masks/lens where the
  dataset has lens drops);
- precision: the share of excluded pixels that are weather; recall: the share of weather pixels
  excluded;
- scene excluded: the share of weather-free pixels that are excluded (structure the loss never sees);
- err vs clean, kept / excluded scene: mean |render - clean| over weather-free pixels the mask keeps,
  and over those it excludes: whether the excluded scene is where the model went wrong;
- brighter by: the mean of render - clean (signed, the channels' mean) over the excluded weather-free
  pixels: above 0, what fills the scene the loss never sees is brighter than the scene;
- detail ratio: the mean gradient magnitude of the clean image on excluded weather-free pixels over
  its mean on all pixels (above 1: the mask takes texture and edges).

--figure OUT.jpg writes, for the first RUN's fourth training view, the weathered image and the clean one
(top), the run's render and its mask (bottom: red = weather excluded, green = scene excluded, grey =
weather kept, black = scene kept).

Usage: mask_log.py WEATHERGS_BINARY DATASET RUN... [--threshold-from RUN] [--figure OUT.jpg]
(writes RUN/renders_train/)
"""
import json
import os
import struct
import subprocess
import sys

import numpy as np
from PIL import Image


def threshold_of(run):
    path = os.path.join(run, "model", "checkpoint.bin")
    with open(path, "rb") as f:
        magic = f.read(8)
        if magic != b"WGSCKPT3":
            sys.exit(f"mask_log.py: {path}: not a format-3 training checkpoint")
        (n,) = struct.unpack("<Q", f.read(8))
        header = json.loads(f.read(n))
    if header.get("robust_bins", 0) == 0:
        return None
    return float(header["robust_threshold"])


def load(path, gray=False):
    a = np.asarray(Image.open(path).convert("L" if gray else "RGB"), dtype=np.float64) / 255.0
    return a


def kept_mask(err, tau):
    inlier = (err < tau).astype(np.int32)
    padded = np.pad(inlier, 1)
    h, w = err.shape
    count = sum(padded[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3))
    return (inlier == 1) | (count * 2 > 9)


def gradient_magnitude(rgb):
    y = rgb.mean(axis=2)
    gx = np.zeros_like(y); gy = np.zeros_like(y)
    gx[:, 1:-1] = (y[:, 2:] - y[:, :-2]) / 2
    gy[1:-1, :] = (y[2:, :] - y[:-2, :]) / 2
    return np.hypot(gx, gy)


def weather_mask(data, view):
    mask = load(os.path.join(data, "masks", "particles", view + ".png"), gray=True) > 0.5
    lens = os.path.join(data, "masks", "lens", view + ".png")
    if os.path.exists(lens):
        mask |= load(lens, gray=True) > 0.5
    return mask


def view_masks(data, renders, view, tau):
    """A training view's render, weathered and clean images, its weather mask and what the rule excludes."""
    render = load(os.path.join(renders, view + ".png"))
    weathered = load(os.path.join(data, "images", view + ".png"))
    clean = load(os.path.join(data, "clean", view + ".png"))
    excluded = ~kept_mask(np.abs(render - weathered).mean(axis=2), tau)
    return render, weathered, clean, weather_mask(data, view), excluded


def write_figure(path, data, renders, view, tau):
    render, weathered, clean, weather, excluded = view_masks(data, renders, view, tau)
    mask = np.zeros_like(render)
    mask[excluded & weather] = (1, 0, 0)
    mask[excluded & ~weather] = (0, 1, 0)
    mask[~excluded & weather] = (0.3, 0.3, 0.3)
    panel = np.concatenate([np.concatenate([weathered, clean], 1), np.concatenate([render, mask], 1)], 0)
    Image.fromarray((panel * 255 + 0.5).astype(np.uint8)).save(path, quality=85)


def main(argv):
    if len(argv) < 3:
        sys.exit(__doc__)
    weathergs, data = argv[0], argv[1]
    runs = argv[2:]
    def take(flag):
        nonlocal runs
        if flag not in runs:
            return None
        i = runs.index(flag)
        if i + 1 >= len(runs):
            sys.exit(f"mask_log.py: {flag} needs a value")
        value = runs[i + 1]
        runs = runs[:i] + runs[i + 2:]
        return value

    source = take("--threshold-from")
    fallback = threshold_of(source) if source else None
    figure = take("--figure")
    dataset = json.load(open(os.path.join(data, "dataset.json")))
    views = dataset["splits"]["train"]
    print("| run | PSNR / SSIM / LPIPS | Gaussians | test PSNR by iteration |")
    print("|---|---|---|---|")
    for run in runs:
        r = json.load(open(os.path.join(run, "results.json")))
        m = r["metrics"]
        points = json.load(open(os.path.join(run, "curve.json")))["points"]
        curve = " ".join(f"{p['iteration']}: {p['psnr']:.2f}" for p in points)
        print(f"| {os.path.basename(os.path.normpath(run))} | {m['psnr']:.2f} / {m['ssim']:.3f} / {m['lpips']:.3f} | "
              f"{r['method_info']['num_gaussians']} | {curve} |")
    print()
    print("| run | tau | excluded | weather share | precision | recall | scene excluded | err vs clean, kept / excluded scene | brighter by | detail ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for run in runs:
        tau = threshold_of(run)
        if tau is None:
            if fallback is None:
                sys.exit(f"mask_log.py: {run} has no robust threshold: give --threshold-from RUN")
            tau = fallback
        out = os.path.join(run, "renders_train")
        if not os.path.isdir(out):
            subprocess.run([weathergs, "--quiet", "render", "--model", os.path.join(run, "model"), "--data", data,
                            "--split", "train", "--out", out], check=True)
        if figure and run == runs[0]:
            write_figure(figure, data, out, views[min(3, len(views) - 1)], tau)
        tot = {k: 0.0 for k in ("px", "excl", "weather", "tp", "scene", "scene_excl", "err_kept", "err_excl", "signed_excl", "grad_excl", "grad_all")}
        for v in views:
            render, _, clean, weather, excluded = view_masks(data, out, v, tau)
            scene = ~weather
            err_clean = np.abs(render - clean).mean(axis=2)
            grad = gradient_magnitude(clean)
            tot["px"] += excluded.size
            tot["excl"] += excluded.sum()
            tot["weather"] += weather.sum()
            tot["tp"] += (excluded & weather).sum()
            tot["scene"] += scene.sum()
            tot["scene_excl"] += (excluded & scene).sum()
            tot["err_kept"] += err_clean[~excluded & scene].sum()
            tot["err_excl"] += err_clean[excluded & scene].sum()
            tot["signed_excl"] += (render - clean).mean(axis=2)[excluded & scene].sum()
            tot["grad_excl"] += grad[excluded & scene].sum()
            tot["grad_all"] += grad.sum()
        t = tot
        kept_scene = t["scene"] - t["scene_excl"]
        detail = (t["grad_excl"] / max(t["scene_excl"], 1)) / (t["grad_all"] / t["px"])
        print(f"| {os.path.basename(os.path.normpath(run))} | {tau:.4f} | {t['excl'] / t['px']:.3f} | {t['weather'] / t['px']:.3f} | "
              f"{t['tp'] / max(t['excl'], 1):.3f} | {t['tp'] / max(t['weather'], 1):.3f} | {t['scene_excl'] / t['scene']:.3f} | "
              f"{t['err_kept'] / max(kept_scene, 1):.4f} / {t['err_excl'] / max(t['scene_excl'], 1):.4f} | {t['signed_excl'] / max(t['scene_excl'], 1):+.4f} | {detail:.2f} |")


if __name__ == "__main__":
    main(sys.argv[1:])
