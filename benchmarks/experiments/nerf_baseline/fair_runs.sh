#!/usr/bin/env bash
# The fair-baseline check (docs/nerf.md, "Against 3DGS on held-out scenes"): the radiance field and
# 3DGS on the clean views of held-out forward-facing scenes (station and village from
# ../convergence/make_tuning_scenes.sh: never benchmark scenes), one thread per run, test snapshots.
# - CELL = <data>:3dgs:<iterations>: the 3DGS oracle, reference schedule scaled to that length.
# - CELL = <data>:nerf:<iterations>[:<options.json>]: nerf-oracle, optionally with --nerf-options.
# Writes benchmarks/baselines/nerf_baseline/<data>_<kind>_<iterations>[_<options stem>].json: the test
# PSNR / SSIM / LPIPS, the curve, the training seconds and the command. A cell whose run is complete
# is only re-read.
# Usage: fair_runs.sh WEATHERGS_BINARY DATA_DIR RUNS_DIR CELL...
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../../.." && pwd)
BIN=$(realpath "${1:?usage: fair_runs.sh WEATHERGS_BINARY DATA_DIR RUNS_DIR CELL...}")
DATA=$(realpath "$2"); RUNS=$(realpath -m "$3"); shift 3
DST="$ROOT/benchmarks/baselines/nerf_baseline"
mkdir -p "$RUNS" "$DST"
for cell in "$@"; do
  IFS=: read -r data kind iterations options <<<"$cell"
  name="${data}_${kind}_${iterations}"
  case "$kind" in
    3dgs) args=(--method oracle --schedule reference --iterations "$iterations") ;;
    nerf) args=(--method nerf-oracle --nerf-iterations "$iterations")
          if [ -n "$options" ]; then args+=(--nerf-options "$options"); name="${name}_$(basename "$options" .json)"; fi ;;
    *) echo "fair_runs.sh: $cell: the kind must be 3dgs or nerf" >&2; exit 2 ;;
  esac
  cmd=("$BIN" --quiet --threads 1 reconstruct --data "$DATA/$data" "${args[@]}" --eval-at-fractions 0.25,0.5,0.75 --out "$RUNS/$name")
  if [ -f "$RUNS/$name/results.json" ]; then echo "fair_runs.sh: $name: complete, re-read" >&2
  else echo "fair_runs.sh: $name" >&2; "${cmd[@]}"; fi
  /usr/bin/python3 - "$RUNS/$name" "$DST/$name.json" "${cmd[*]}" "$BIN" "$DATA" "$RUNS" "$ROOT" <<'PY'
import json, sys, os
run, dst, cmd, binary, data, runs, root = sys.argv[1:]
# The command as a user would type it: paths relative to the tool, the data and the runs.
cmd = cmd.replace(binary, "weathergs").replace(data + "/", "DATA/").replace(runs + "/", "RUNS/").replace(root + "/", "")
r = json.load(open(os.path.join(run, "results.json")))
c = json.load(open(os.path.join(run, "curve.json")))
m = r["metrics"]
mi = r["method_info"]
out = {"cell": os.path.basename(dst)[:-5], "command": cmd, "weathergs_commit": mi.get("weathergs_commit"),
       "final": {"psnr": m["psnr"], "ssim": m["ssim"], "lpips": m.get("lpips"),
                 "train_seconds": mi.get("train_seconds"), "peak_rss_mb": mi.get("peak_rss_mb")},
       "curve": c.get("points", c)}
tmp = dst + ".tmp"
json.dump(out, open(tmp, "w"), indent=1)
os.replace(tmp, dst)
PY
done
