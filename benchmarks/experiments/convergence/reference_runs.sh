#!/usr/bin/env bash
# The convergence study's runs (docs/record/convergence.md), one thread per run, with test snapshots.
# - CELL = <dataset folder under DATA_DIR>:<method>: a frozen reference, the trainer at 30,000
#   iterations (`--schedule reference`) with snapshots at 500 ... 25,000; writes
#   benchmarks/baselines/convergence/<data>_<method>.json.
# - CELL = <data>:<method>:fast: the default fast schedule at its own length, snapshots every 1000
#   iterations; writes benchmarks/baselines/convergence/fast/<data>_<method>.json.
# - CELL = <data>:<method>:<iterations>: a tuning run of the reference schedule scaled to that length,
#   with snapshots at fifths of the run; writes benchmarks/baselines/convergence/tuning/<data>_<method>_<iterations>.json.
#   Tuning scenes only (make_tuning_scenes.sh), never benchmark scenes.
# - CELL = <data>:<method>:<iterations>:<options.json>: the same with `--train-options options.json` (a
#   candidate schedule), named <data>_<method>_<iterations>_<options file stem>.
# Resumable: a run stopped part way resumes from its last checkpoint when the script runs again (the
# checkpoint keeps the training seconds, so they stay the training time of one uninterrupted run).
# Usage: reference_runs.sh WEATHERGS_BINARY DATA_DIR RUNS_DIR CELL...
# Each JSON holds the final and best test PSNR / SSIM / LPIPS, the training seconds, the Gaussian
# count, the curve, the command, and how the machine was shared while it ran (TIMING_NOTE: training
# seconds are only comparable under the same).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../../.." && pwd)
BIN=$(realpath "${1:?usage: reference_runs.sh WEATHERGS_BINARY DATA_DIR RUNS_DIR CELL...}")
DATA=$(realpath "$2"); RUNS=$(realpath -m "$3"); shift 3
DST="$ROOT/benchmarks/baselines/convergence"
mkdir -p "$RUNS" "$DST/tuning" "$DST/fast"
for cell in "$@"; do
  IFS=: read -r data method iterations options <<<"$cell"
  if [ -z "$iterations" ]; then
    name="${data}_${method}"; dst="$DST/$name.json"
    length=(--schedule reference --iterations 30000)
    eval_at=500,1000,2000,3000,5000,7000,10000,15000,20000,25000
  elif [ "$iterations" = fast ]; then
    name="${data}_${method}"; dst="$DST/fast/$name.json"; name="${name}_fast"
    # Every 1000 iterations before the end of the fast length (TrainOptions::with_run_length: 500
    # passes over the training views, rounded up to 100, within 3000..30000); reconstruct refuses
    # an --eval-at past it.
    fast_length=$(/usr/bin/python3 -c 'import json, sys; t = len(json.load(open(sys.argv[1]))["splits"]["train"]); print(min(30000, max(3000, (500 * t + 99) // 100 * 100)))' "$DATA/$data/dataset.json")
    length=(); eval_at=$(seq -s, 1000 1000 $((fast_length - 1)))
  else
    name="${data}_${method}_${iterations}${options:+_$(basename "$options" .json)}"; dst="$DST/tuning/$name.json"
    length=(--iterations "$iterations")  # a candidate's file names its schedule
    [ -n "${options:-}" ] || length=(--schedule reference "${length[@]}")
    eval_at=$((iterations / 5)),$((2 * iterations / 5)),$((3 * iterations / 5)),$((4 * iterations / 5))
  fi
  out="$RUNS/$name"
  cmd=("$BIN" --quiet --threads 1 reconstruct --data "$DATA/$data" --method "$method" "${length[@]}"
       --eval-at "$eval_at" --checkpoint-every 500 --seed 0 --out "$out")
  [ -z "${options:-}" ] || cmd+=(--train-options "$(realpath "$options")")
  if [ ! -f "$out/results.json" ]; then
    echo "== $name: ${cmd[*]}"
    "${cmd[@]}"
  fi
  /usr/bin/python3 - "$out" "$dst" "$cell" "${cmd[*]}" \
    "${TIMING_NOTE:-one thread per run (--threads 1), two runs at a time on the 2-core machine}" <<'PY'
import json, sys
run, dst, cell, cmd, timing = sys.argv[1:]
res = json.load(open(f"{run}/results.json"))
curve = json.load(open(f"{run}/curve.json"))["points"]
best = max(curve, key=lambda p: p["psnr"])
m = res["method_info"]
out = {"cell": cell, "command": cmd.replace(run, "RUN"),
       "timing": timing,
       "R": {"final": res["metrics"], "best": {k: best[k] for k in ("iteration", "psnr", "ssim", "lpips")}},
       "C_train_seconds": m.get("train_seconds"), "num_gaussians": m.get("num_gaussians"),
       "iterations": m.get("iterations"), "weathergs_commit": m.get("weathergs_commit"),
       "curve": [{k: p[k] for k in ("iteration", "train_seconds", "psnr", "ssim", "lpips", "num_gaussians")} for p in curve]}
json.dump(out, open(dst, "w"), indent=1)
open(dst, "a").write("\n")
print(f"{dst}: PSNR {res['metrics']['psnr']:.2f} (best {best['psnr']:.2f} at {best['iteration']}), "
      f"LPIPS {res['metrics']['lpips']:.4f}, {m.get('train_seconds'):.0f} s, {m.get('num_gaussians')} Gaussians")
PY
done
