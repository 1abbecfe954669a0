#!/usr/bin/python3
"""What accuracy costs in time: test PSNR against training seconds, per variant, for every method.

Reads the curve.json files that `weathergs reconstruct --eval-at ...` writes (docs/methods.md) and
writes OUT_CSV (one row per point: variant, method, seed, iteration, train_seconds, psnr, ssim,
lpips, num_gaussians) and one PNG per variant in OUT_DIR (<variant>.png): PSNR against training
seconds, one line per method through the mean over its seeds at each iteration; reference methods
(oracle, gt-masks, nerf-oracle) dashed.

Usage: plot_curves.py --csv OUT_CSV --png-dir OUT_DIR CURVE.json [CURVE.json ...]"""
import argparse
import csv
import json
import os
import sys
import tempfile
from collections import defaultdict

REFERENCE = {"oracle", "gt-masks", "nerf-oracle"}
COLUMNS = ["variant", "method", "seed", "iteration", "train_seconds", "psnr", "ssim", "lpips", "num_gaussians"]


def fail(path, message):
    sys.exit(f"error: {path}: {message}")


def read_curve(path):
    try:
        with open(path, encoding="utf8") as f:
            c = json.load(f)
    except (OSError, json.JSONDecodeError) as e:
        fail(path, f"cannot read a curve: {e}")
    if c.get("format") != "weathergs-curve" or c.get("version") != 1:
        fail(path, "expected format weathergs-curve, version 1")
    for key in ("method", "dataset", "seed", "points"):
        if key not in c:
            fail(path, f"missing key '{key}'")
    if not c["points"]:
        fail(path, "has no points")
    return c


def write_atomic(path, write):
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=folder, suffix=os.path.splitext(path)[1])
    os.close(fd)
    try:
        write(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; the result is an ordinary file
        os.replace(tmp, path)
    except BaseException:
        os.unlink(tmp)
        raise


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--csv", required=True)
    ap.add_argument("--png-dir", required=True)
    ap.add_argument("curves", nargs="+")
    args = ap.parse_args()

    rows = []
    for path in args.curves:
        c = read_curve(path)
        for p in c["points"]:
            rows.append({"variant": c["dataset"], "method": c["method"], "seed": c["seed"],
                         "iteration": p["iteration"], "train_seconds": p["train_seconds"], "psnr": p["psnr"],
                         "ssim": p["ssim"], "lpips": p.get("lpips"), "num_gaussians": p.get("num_gaussians")})
    rows.sort(key=lambda r: (r["variant"], r["method"], r["seed"], r["iteration"]))

    def write_csv(tmp):
        with open(tmp, "w", newline="", encoding="utf8") as f:
            w = csv.DictWriter(f, fieldnames=COLUMNS, lineterminator="\n")
            w.writeheader()
            for r in rows:
                w.writerow({k: ("" if r[k] is None else r[k]) for k in COLUMNS})
    write_atomic(args.csv, write_csv)

    import matplotlib
    matplotlib.use("Agg")  # no display on the benchmark machines
    import matplotlib.pyplot as plt

    by_variant = defaultdict(lambda: defaultdict(lambda: defaultdict(list)))
    for r in rows:
        by_variant[r["variant"]][r["method"]][r["iteration"]].append(r)
    for variant, methods in sorted(by_variant.items()):
        fig, ax = plt.subplots(figsize=(6.4, 4.2), dpi=120)
        for method, points in sorted(methods.items(), key=lambda kv: (kv[0] in REFERENCE, kv[0])):
            its = sorted(points)
            secs = [sum(p["train_seconds"] for p in points[i]) / len(points[i]) for i in its]
            psnr = [sum(p["psnr"] for p in points[i]) / len(points[i]) for i in its]
            seeds = max(len(points[i]) for i in its)
            label = method + (f" ({seeds} seeds)" if seeds > 1 else "")
            ax.plot(secs, psnr, "--o" if method in REFERENCE else "-o", label=label, markersize=4)
        # Log seconds: the radiance-field methods train ~10x longer than 3DGS on the same variant.
        ax.set_xscale("log")
        ax.set_xlabel("training time (s, log scale)")
        ax.set_ylabel("test PSNR vs clean (dB)")
        ax.set_title(f"{variant}: accuracy against training time")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        write_atomic(os.path.join(args.png_dir, variant + ".png"), lambda tmp: fig.savefig(tmp, format="png"))
        plt.close(fig)
    print(f"wrote {args.csv} ({len(rows)} points) and {len(by_variant)} plot(s) in {args.png_dir}")


if __name__ == "__main__":
    main()
