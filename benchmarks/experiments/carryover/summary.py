#!/usr/bin/env python3
"""carryover.sh's table: each layout's four runs beside the benchmark's rain variants from the archive.

Usage: summary.py OUT_DIR ARCHIVE BENCH_RUNS LAYOUT...   (LAYOUT: name:index:f_number:focus_m; BENCH_RUNS
may be '' when the benchmark's run folders are gone: its LED columns then read n/a)

Per row: 3dgs, weathergs, gt-masks and oracle as PSNR / SSIM / LPIPS, WeatherGS's PSNR gain over 3DGS,
that gain as a share of the oracle's gap, the LED's IoU / precision against the true lens drops and
whether the silent-LED warning fired. The last lines say how much of the benchmark's mean gain and
mean share each layout keeps.
"""
import json
import math
import os
import sys

METHODS = ("3dgs", "weathergs", "gt-masks", "oracle")
BENCH_RAIN = ("tanabata_rain", "factory_rain", "pool_rain")


def fail(msg):
    print(f"summary.py: {msg}", file=sys.stderr)
    sys.exit(2)


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        fail(f"{path}: {e}")


def row(label, results, detect_path):
    """One table row, and (gain, share) for the summary lines; results maps method -> results.json."""
    met = {m: results[m]["metrics"] for m in METHODS}
    cell = lambda m: f"{met[m]['psnr']:.2f} / {met[m]['ssim']:.3f} / {met[m]['lpips']:.3f}"
    gain = met["weathergs"]["psnr"] - met["3dgs"]["psnr"]
    gap = met["oracle"]["psnr"] - met["3dgs"]["psnr"]
    share = gain / gap if gap > 0 else math.nan
    led = "n/a"
    if detect_path and os.path.exists(detect_path):
        gt = load(detect_path).get("ground_truth") or {}
        if gt:
            led = f"{gt['iou']:.3f} / {gt['precision']:.3f}"
    warn = results["weathergs"]["method_info"].get("warnings", [])
    line = (f"| {label} | {cell('3dgs')} | {cell('weathergs')} | {cell('gt-masks')} | {cell('oracle')} "
            f"| {gain:+.2f} dB | {share:.0%} of {gap:.2f} dB | {led} | {'yes: ' + warn[0][:60] if warn else 'no'} |")
    return line, gain, share


def main():
    if len(sys.argv) < 5:
        fail("usage: summary.py OUT_DIR ARCHIVE BENCH_RUNS LAYOUT...")
    out, archive, bench_runs, layouts = sys.argv[1], sys.argv[2], sys.argv[3], [l.split(":") for l in sys.argv[4:]]
    print("| data (optics) | 3dgs | weathergs | gt-masks | oracle | gain | share of the oracle's gap "
          "| LED IoU / precision | silent-LED warning |")
    print("|---|---|---|---|---|---|---|---|---|")
    bench = []
    for v in BENCH_RAIN:
        paths = {m: f"{archive}/{v}/{m}/seed0/results.json" for m in METHODS}
        missing = [m for m, p in paths.items() if not os.path.exists(p)]
        if missing:
            print(f"| benchmark {v} | not archived yet: {', '.join(missing)} | | | | | | | |")
            continue
        det = f"{bench_runs}/{v}/weathergs/seed0/detected/detect.json" if bench_runs else ""
        line, gain, share = row(f"benchmark {v} (f/2.8, focus 2 m)", {m: load(p) for m, p in paths.items()}, det)
        print(line)
        bench.append((gain, share))
    kept = []
    for name, _, fnum, focus in layouts:
        d = f"{out}/runs/{name}_wet"
        paths = {m: f"{d}/{m}/results.json" for m in METHODS}
        missing = [m for m, p in paths.items() if not os.path.exists(p)]
        if missing:
            print(f"| {name} | not run yet: {', '.join(missing)} | | | | | | | |")
            continue
        line, gain, share = row(f"{name} (f/{fnum}, focus {focus} m)", {m: load(p) for m, p in paths.items()},
                                f"{d}/weathergs/detected/detect.json")
        print(line)
        kept.append((name, gain, share))
    if bench and kept:
        g = sum(b[0] for b in bench) / len(bench)
        s = sum(b[1] for b in bench) / len(bench)
        print(f"\nThe benchmark's rain variants ({len(bench)} of {len(BENCH_RAIN)}): mean gain {g:+.2f} dB, "
              f"mean share of the oracle's gap {s:.0%}.")
        for name, gain, share in kept:
            print(f"- {name} keeps {gain / g:.0%} of the mean gain ({gain:+.2f} dB) and has {share:.0%} of its "
                  f"oracle's gap against the benchmark's {s:.0%}.")


if __name__ == "__main__":
    main()
