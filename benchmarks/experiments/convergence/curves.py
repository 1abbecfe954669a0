#!/usr/bin/python3
"""The convergence study's curves and table, from the committed run JSONs (reference_runs.sh).

For every cell with a 30,000-iteration reference (benchmarks/baselines/convergence/<cell>.json) and
a fast run (fast/<cell>.json): test PSNR against training seconds for both (one PNG per cell in
OUT_DIR, all points in one CSV), and a Markdown table on stdout: R (the reference's final), the fast
run's final, the aim (PSNR >= R - 0.3 dB, LPIPS <= R + 0.01, within 10% of C; weathered cells two-sided,
|fast - R| <= 0.3 dB) and the training seconds at which each run first reached R - 0.3 dB (a snapshot's,
so a bound to within the snapshot spacing).
Usage: curves.py BASELINES_DIR OUT_DIR CSV
"""
import csv
import json
import os
import sys

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PSNR_SLACK_DB, LPIPS_SLACK, COST_SHARE = 0.3, 0.01, 0.10
CLEAN_METHODS = {"oracle"}  # trained on the clean images: the one-sided aim


def first_reaching(curve, target):
    for p in curve:
        if p["psnr"] >= target:
            return p["train_seconds"]
    return None


def main(base, out_dir, csv_path):
    os.makedirs(out_dir, exist_ok=True)
    rows, table = [], []
    for name in sorted(os.listdir(os.path.join(base, "fast"))):
        cell = name[:-len(".json")]
        ref_path = os.path.join(base, name)
        fast = json.load(open(os.path.join(base, "fast", name)))
        ref = json.load(open(ref_path)) if os.path.exists(ref_path) else None
        runs = [("fast", fast)] + ([("reference", ref)] if ref else [])
        for label, run in runs:
            for p in run["curve"]:
                rows.append([cell, label, p["iteration"], p["train_seconds"], p["psnr"], p["ssim"], p["lpips"],
                             p["num_gaussians"]])
        f = fast["curve"][-1]
        if ref is None:
            table.append(f"| {cell} | not run | {f['psnr']:.2f} / {f['lpips']:.4f} | {fast['C_train_seconds']:.0f} s, "
                         f"{f['num_gaussians']:,} G | | | no reference yet |")
            continue
        r = ref["R"]["final"]
        clean = cell.rsplit("_", 1)[-1] in CLEAN_METHODS
        dpsnr = f["psnr"] - r["psnr"]
        share = fast["C_train_seconds"] / ref["C_train_seconds"]
        meets = (dpsnr >= -PSNR_SLACK_DB if clean else abs(dpsnr) <= PSNR_SLACK_DB) and \
            f["lpips"] <= r["lpips"] + LPIPS_SLACK and share <= COST_SHARE
        target = r["psnr"] - PSNR_SLACK_DB
        tf, tr = first_reaching(fast["curve"], target), first_reaching(ref["curve"], target)
        fmt = lambda t: "never" if t is None else f"{t:.0f} s"
        table.append(f"| {cell} | {r['psnr']:.2f} / {r['lpips']:.4f} | {f['psnr']:.2f} / {f['lpips']:.4f} "
                     f"({dpsnr:+.2f} dB) | {fast['C_train_seconds']:.0f} s of {ref['C_train_seconds']:.0f} s "
                     f"({100 * share:.1f}%), {f['num_gaussians']:,} G | {fmt(tf)} | {fmt(tr)} | "
                     f"{'meets' if meets else 'misses'} |")
        plt.figure(figsize=(6, 3.6))
        for label, run, style in [("reference (30,000)", ref, "-o"), ("fast", fast, "-s")]:
            c = run["curve"]
            plt.plot([p["train_seconds"] for p in c], [p["psnr"] for p in c], style, ms=3, label=label)
        plt.axhline(target, color="grey", ls="--", lw=0.8, label="R - 0.3 dB")
        plt.xscale("log")
        plt.xlabel("training seconds (one thread)")
        plt.ylabel("test PSNR (dB)")
        plt.title(cell)
        plt.legend(fontsize=8)
        plt.tight_layout()
        plt.savefig(os.path.join(out_dir, f"convergence_{cell}.png"), dpi=90)
        plt.close()
    with open(csv_path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["cell", "schedule", "iteration", "train_seconds", "psnr", "ssim", "lpips", "num_gaussians"])
        w.writerows(rows)
    print("| cell | R: PSNR / LPIPS | fast: PSNR / LPIPS | fast cost | fast reaches R - 0.3 | reference reaches it | aim |")
    print("|---|---|---|---|---|---|---|")
    print("\n".join(table))


if __name__ == "__main__":
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    main(*sys.argv[1:])
