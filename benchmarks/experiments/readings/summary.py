#!/usr/bin/python3
"""Tables of the readings experiments from training.sh's runs (READINGS_DIR/runs/<data>/<kind>/):
test PSNR / SSIM / LPIPS against clean/ and the training's CPU seconds, per dataset, and for each
reading the differences it is about. Runs not made yet are shown as '–'.

Usage: summary.py READINGS_DIR
"""
import json
import os
import sys


def metrics(path):
    if not os.path.exists(path):
        return None
    r = json.load(open(path))
    m, info = r["metrics"], r.get("method_info", {})
    return {"psnr": m["psnr"], "ssim": m["ssim"], "lpips": m.get("lpips"), "cpu": info.get("train_cpu_seconds"),
            "wall": info.get("train_seconds")}


def cell(m):
    if m is None:
        return "–"
    cpu = f", {m['cpu']:.0f} CPU-s" if m.get("cpu") is not None else ""
    return f"{m['psnr']:.2f} / {m['ssim']:.3f} / {m['lpips']:.3f}{cpu}"


def diff(a, b):
    if a is None or b is None:
        return "–"
    return f"{a['psnr'] - b['psnr']:+.2f} dB, LPIPS {a['lpips'] - b['lpips']:+.3f}"


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    runs = os.path.join(sys.argv[1], "runs")
    kinds = ["3dgs", "weathergs-no-led", "no-particles", "gs-w-lite", "gs-w-lite-novis", "nerf", "derainnerf", "weathergs"]
    data = sorted(d for d in os.listdir(runs) if os.path.isdir(os.path.join(runs, d))) if os.path.isdir(runs) else []
    r = {d: {k: metrics(os.path.join(runs, d, k, "results.json")) for k in kinds} for d in data}
    print("| dataset | " + " | ".join(kinds) + " |")
    print("|---|" + "---|" * len(kinds))
    for d in data:
        print(f"| {d} | " + " | ".join(cell(r[d][k]) for k in kinds) + " |")
    print()
    print("| dataset | AEF-filtered − 3dgs | no-particles − 3dgs | gs-w-lite − 3dgs | gs-w-lite-novis − 3dgs | derainnerf − nerf |")
    print("|---|---|---|---|---|---|")
    for d in data:
        x = r[d]
        print(f"| {d} | {diff(x['weathergs-no-led'], x['3dgs'])} | {diff(x['no-particles'], x['3dgs'])} | "
              f"{diff(x['gs-w-lite'], x['3dgs'])} | {diff(x['gs-w-lite-novis'], x['3dgs'])} | {diff(x['derainnerf'], x['nerf'])} |")
    # The rain gain against the rain's intensity: heavy is the tuning scene's own.
    rows = []
    for d in data:
        if not d.endswith("_rain"):
            continue
        heavy = (r[d]["3dgs"], r[d]["weathergs"])
        rows.append((d, "heavy", *heavy))
        for intensity in ("moderate", "light"):
            base = os.path.join(runs, d, "rain-" + intensity)
            rows.append((d, intensity, metrics(os.path.join(base, "3dgs", "results.json")),
                         metrics(os.path.join(base, "weathergs", "results.json"))))
    if rows:
        print()
        print("| dataset | rain | 3dgs | weathergs | weathergs − 3dgs |")
        print("|---|---|---|---|---|")
        for d, intensity, a, b in rows:
            print(f"| {d} | {intensity} | {cell(a)} | {cell(b)} | {diff(b, a)} |")


if __name__ == "__main__":
    main()
