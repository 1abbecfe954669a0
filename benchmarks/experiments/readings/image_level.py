#!/usr/bin/python3
"""The readings that disagree with the paper, measured on the images before any training (tuning
scenes only, never the benchmark's; docs/record/readings.md).

Per dataset (its training views):
- the weathered images and the AEF's output (`weathergs filter`, learned, the selector choosing)
  scored against clean/ and against the generator's no_particles target (particles gone, lens drops
  kept): PSNR, SSIM, LPIPS; and the detail left, as the variance of the Laplacian of the luminance
  relative to clean/'s (1 = as sharp as the scene, below 1 = smoother);
- the LED's masks, averaged over the training views (weathergs) and per view (derainnerf,
  `detect --per-view`): the share of the image they mask, their IoU and precision against the true
  lens drops (masks/lens), and the share of the falling particles (masks/particles) they cover.

The weathered datasets are made again from TUNING_DIR (the output of
benchmarks/experiments/convergence/make_tuning_scenes.sh: clear_<scene>_<variant>/, rain.json,
snow.json) with `weathergs weather --targets`, which the no_particles score needs; the weather is
deterministic, so their images are the tuning datasets' own.

Usage: image_level.py WEATHERGS_BINARY TUNING_DIR OUT_DIR SCENE_WEATHER...   (e.g. village_rain
station_snow; writes OUT_DIR/image_level.json and prints a Markdown table; finished steps are kept,
so it resumes)
"""
import json
import os
import subprocess
import sys

import numpy as np
from PIL import Image


def run(cmd, log):
    with open(log, "w") as f:
        if subprocess.call(cmd, stdout=f, stderr=subprocess.STDOUT) != 0:
            sys.exit(f"error: {' '.join(cmd)} failed; see {log}")


def load(path, gray=False):
    im = Image.open(path)
    return np.asarray(im.convert("L" if gray else "RGB"), dtype=np.float64) / 255.0


def laplacian_variance(img):
    """Variance of the 4-neighbour Laplacian of the luminance: the image's fine detail."""
    y = img @ np.array([0.2126, 0.7152, 0.0722])
    lap = -4 * y[1:-1, 1:-1] + y[:-2, 1:-1] + y[2:, 1:-1] + y[1:-1, :-2] + y[1:-1, 2:]
    return float(lap.var())


def train_views(folder, views, link_dir):
    """evaluate refuses renders of views outside its split: the training views' images, linked."""
    os.makedirs(link_dir, exist_ok=True)
    for v in views:
        link = os.path.join(link_dir, v + ".png")
        if not os.path.lexists(link):
            os.symlink(os.path.join(folder, v + ".png"), link)
    return link_dir


def scored(binary, data, renders, target, out, log):
    if not os.path.exists(out):
        run([binary, "--quiet", "evaluate", "--gt", data, "--renders", renders, "--method", os.path.basename(renders), "--split", "train",
             "--ground-truth", target, "-o", out], log)
    m = json.load(open(out))["metrics"]
    return {k: m[k] for k in ("psnr", "ssim", "lpips")}


def mask_stats(mask_dir, data, views):
    covered = hit = union = particle_total = particle_hit = 0.0
    pixels = 0
    for v in views:
        m = load(os.path.join(mask_dir, v + ".png"), gray=True) > 0.5
        lens_path = os.path.join(data, "masks", "lens", v + ".png")
        lens = load(lens_path, gray=True) > 0.5 if os.path.exists(lens_path) else np.zeros_like(m)
        part = load(os.path.join(data, "masks", "particles", v + ".png"), gray=True) > 0.5
        pixels += m.size
        covered += m.sum()
        hit += (m & lens).sum()
        union += (m | lens).sum()
        particle_total += part.sum()
        particle_hit += (m & part).sum()
    return {"masked_share": covered / pixels,
            "lens_iou": hit / union if union else None,
            "lens_precision": hit / covered if covered else None,
            "particles_covered": particle_hit / particle_total if particle_total else None}


def main():
    if len(sys.argv) < 5:
        sys.exit(__doc__)
    binary, tuning, out = (os.path.realpath(a) for a in sys.argv[1:4])
    os.makedirs(out, exist_ok=True)
    rows = {}
    for name in sys.argv[4:]:
        scene, weather = name.rsplit("_", 1)
        variant = {"rain": "wet", "snow": "snowy"}[weather]
        clear, spec = os.path.join(tuning, f"clear_{scene}_{variant}"), os.path.join(tuning, weather + ".json")
        for path in (clear, spec):
            if not os.path.exists(path):
                sys.exit(f"error: {path}: missing (make_tuning_scenes.sh makes it)")
        work = os.path.join(out, name)
        data = os.path.join(work, "data")
        os.makedirs(work, exist_ok=True)
        if not os.path.exists(os.path.join(data, "dataset.json")):
            run([binary, "--quiet", "weather", "--in", clear, "--spec", spec, "--targets", "--out", data], os.path.join(work, "weather.log"))
        views = json.load(open(os.path.join(data, "dataset.json")))["splits"]["train"]
        filtered = os.path.join(work, "filtered")
        if not os.path.exists(os.path.join(filtered, "filter.json")):
            run([binary, "--quiet", "--threads", "1", "filter", "--data", data, "--out", filtered], os.path.join(work, "filter.log"))
        record = json.load(open(os.path.join(filtered, "filter.json")))
        row = {"views": len(views), "aef": record.get("selection", {}).get("scene_plugin", record.get("task"))}
        for label, renders in (("weathered", os.path.join(data, "images")), ("filtered", filtered)):
            linked = train_views(renders, views, os.path.join(work, label + "_train"))
            row[label] = {t: scored(binary, data, linked, t, os.path.join(work, f"{label}_{t}.json"), os.path.join(work, f"{label}_{t}.log"))
                          for t in ("clean", "no_particles")}
            row[label]["detail"] = float(np.mean([laplacian_variance(load(os.path.join(renders, v + ".png"))) /
                                                  laplacian_variance(load(os.path.join(data, "clean", v + ".png"))) for v in views]))
        for label, flags in (("led_averaged", []), ("led_per_view", ["--per-view"])):
            masks = os.path.join(work, label)
            if not os.path.exists(os.path.join(masks, "detect.json")):
                run([binary, "--quiet", "--threads", "1", "detect", "--data", data, "--out", masks] + flags, os.path.join(work, label + ".log"))
            row[label] = mask_stats(masks, data, views)
        rows[name] = row
    tmp = os.path.join(out, "image_level.json.tmp")
    json.dump(rows, open(tmp, "w"), indent=1)
    os.replace(tmp, os.path.join(out, "image_level.json"))

    f = lambda x, d=3: "–" if x is None else f"{x:.{d}f}"
    print("| dataset | AEF task | weathered vs clean PSNR / SSIM / LPIPS | filtered vs clean | filtered vs no_particles | detail weathered / filtered | LED averaged: masked / lens IoU / precision / particles covered | LED per view: the same |")
    print("|---|---|---|---|---|---|---|---|")
    for name, r in rows.items():
        m = lambda x: f"{x['psnr']:.2f} / {x['ssim']:.3f} / {f(x['lpips'])}"
        led = lambda x: f"{x['masked_share']:.2%} / {f(x['lens_iou'])} / {f(x['lens_precision'])} / {f(x['particles_covered'])}"
        print(f"| {name} | {r['aef']} | {m(r['weathered']['clean'])} | {m(r['filtered']['clean'])} | {m(r['filtered']['no_particles'])} "
              f"| {r['weathered']['detail']:.2f} / {r['filtered']['detail']:.2f} | {led(r['led_averaged'])} | {led(r['led_per_view'])} |")


if __name__ == "__main__":
    main()
