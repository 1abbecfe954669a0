#!/usr/bin/env bash
# The frozen references of the convergence study (docs/reconstruction.md, "Schedule for short runs"): the trainer as it stands
# (the 30,000-iteration reference schedule) once per cell, with snapshots, one thread per run.
# Resumable: a run stopped part way resumes from its last checkpoint when the script runs again (the
# checkpoint keeps the training seconds, so C stays the training time of one uninterrupted run).
# Usage: reference_runs.sh WEATHERGS_BINARY DATA_DIR RUNS_DIR CELL...
#   CELL = <dataset folder name under DATA_DIR>:<method>, e.g. station_rain:oracle
# Writes RUNS_DIR/<cell>/ (the run) and, when it completes, benchmarks/baselines/convergence/<cell>.json:
# R (final and best test PSNR / SSIM / LPIPS), C (training seconds), the Gaussian count, the command,
# and how the machine was shared while it ran (TIMING_NOTE: C is only comparable under the same).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../../.." && pwd)
BIN=$(realpath "${1:?usage: reference_runs.sh WEATHERGS_BINARY DATA_DIR RUNS_DIR CELL...}")
DATA=$(realpath "$2"); RUNS=$(realpath -m "$3"); shift 3
ITERATIONS=${ITERATIONS:-30000}
EVAL_AT=${EVAL_AT:-500,1000,2000,3000,5000,7000,10000,15000,20000,25000}
mkdir -p "$RUNS" "$ROOT/benchmarks/baselines/convergence"
for cell in "$@"; do
  data=${cell%%:*}; method=${cell##*:}; name="${data}_${method}"
  out="$RUNS/$name"
  cmd=("$BIN" --quiet --threads 1 reconstruct --data "$DATA/$data" --method "$method" --iterations "$ITERATIONS"
       --eval-at "$EVAL_AT" --checkpoint-every 500 --seed 0 --out "$out")
  if [ ! -f "$out/results.json" ]; then
    echo "== $name: ${cmd[*]}"
    "${cmd[@]}"
  fi
  /usr/bin/python3 - "$out" "$ROOT/benchmarks/baselines/convergence/$name.json" "$data" "$method" "${cmd[*]}" \
    "${TIMING_NOTE:-one thread per run (--threads 1), two runs at a time on the 2-core machine}" <<'PY'
import json, sys
run, dst, data, method, cmd, timing = sys.argv[1:]
res = json.load(open(f"{run}/results.json"))
curve = json.load(open(f"{run}/curve.json"))["points"]
best = max(curve, key=lambda p: p["psnr"])
m = res["method_info"]
out = {"cell": f"{data}:{method}", "command": cmd.replace(run, "RUN"),
       "timing": timing,
       "R": {"final": res["metrics"], "best": {k: best[k] for k in ("iteration", "psnr", "ssim", "lpips")}},
       "C_train_seconds": m.get("train_seconds"), "num_gaussians": m.get("num_gaussians"),
       "iterations": m.get("iterations"), "weathergs_commit": m.get("weathergs_commit"),
       "curve": [{k: p[k] for k in ("iteration", "train_seconds", "psnr", "ssim", "lpips", "num_gaussians")} for p in curve]}
json.dump(out, open(dst, "w"), indent=1)
open(dst, "a").write("\n")
print(f"{dst}: PSNR {res['metrics']['psnr']:.2f} (best {best['psnr']:.2f} at {best['iteration']}), C {m.get('train_seconds'):.0f} s")
PY
done
