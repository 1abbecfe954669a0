#!/usr/bin/env bash
# Why robust-3dgs falls below 3DGS on snow (docs/record/robust_snow.md), on a tuning scene, seed 0, one
# thread per run: robust-3dgs as the archive runs it (robust), robust-3dgs with the reference's own loss
# (robust-l1: L1 only, averaged over all pixels, i.e. SpotLessSplats' robust loss), robust-3dgs with
# 3DGS's opacity reset (robust-reset: once at iteration 2999, where the fast schedule resets 3dgs at
# 3000; a robust run keeps the reference's no-reset unless the interval is set by hand) and 3dgs, then what
# the RobustFilter mask excludes at the end of training (mask_log.py, with a figure).
# Usage: run.sh WEATHERGS_BINARY DATASET OUT_DIR   (a finished run is kept, a stopped one resumes)
set -euo pipefail
W=$(realpath "${1:?usage: run.sh WEATHERGS_BINARY DATASET OUT_DIR}")
DATA=$(realpath "${2:?usage: run.sh WEATHERGS_BINARY DATASET OUT_DIR}")
OUT=$(realpath -m "${3:?usage: run.sh WEATHERGS_BINARY DATASET OUT_DIR}")
HERE=$(dirname "$(realpath "$0")")
[ -f "$DATA/dataset.json" ] || { echo "run.sh: $DATA/dataset.json: missing (a dataset folder is needed)" >&2; exit 2; }
[ -d "$DATA/masks/particles" ] || { echo "run.sh: $DATA/masks/particles: missing (the true particle masks are needed)" >&2; exit 2; }
mkdir -p "$OUT"
echo '{"lambda_dssim": 0, "mask_normalization": "reference"}' > "$OUT/robust-l1.json"
echo '{"opacity_reset_interval": 2999}' > "$OUT/robust-reset.json"
reconstruct() {  # NAME METHOD [more flags]
  local name=$1 method=$2; shift 2
  [ -f "$OUT/$name/results.json" ] && return 0
  echo "== $(date -Is) $name"
  "$W" --quiet --threads 1 reconstruct --data "$DATA" --method "$method" --seed 0 --out "$OUT/$name" \
    --eval-at-fractions 0.125,0.25,0.5 "$@" > "$OUT/$name.log" 2>&1 || { echo "run.sh: $name failed: $OUT/$name.log" >&2; exit 1; }
}
reconstruct robust robust-3dgs
reconstruct robust-l1 robust-3dgs --train-options "$OUT/robust-l1.json"
reconstruct robust-reset robust-3dgs --train-options "$OUT/robust-reset.json"
reconstruct 3dgs 3dgs
/usr/bin/python3 "$HERE/mask_log.py" "$W" "$DATA" "$OUT/robust" "$OUT/robust-l1" "$OUT/robust-reset" "$OUT/3dgs" --threshold-from "$OUT/robust" \
  --figure "$OUT/mask.jpg"
