#!/usr/bin/env bash
# What separates perfect masks from the oracle (docs/carryover.md, "Perfect masks are not the oracle"), on
# a tuning scene, never the benchmark's: 3DGS at the fast schedule, seed 0, one thread a run, in the four
# cells of {weathered images with the true particle and lens masks out of the loss, clean images} x
# {SfM points of the weathered views (sparse/0), of the clean views (sparse_clean/0)}:
#   gt-masks            reconstruct --method gt-masks    (weathered images + masks, weathered points)
#   gt-masks-cleanpts   train --masks all --points-dir sparse_clean/0
#   clean-weatherpts    train --images-dir clean         (clean images, weathered points)
#   oracle              reconstruct --method oracle      (clean images, clean points)
# Usage: oracle_gap.sh WEATHERGS_BINARY DATASET OUT_DIR   (a finished run is kept, a stopped one resumes;
# prints a Markdown table of the test scores)
set -euo pipefail
W=$(realpath "${1:?usage: oracle_gap.sh WEATHERGS_BINARY DATASET OUT_DIR}")
DATA=$(realpath "${2:?usage: oracle_gap.sh WEATHERGS_BINARY DATASET OUT_DIR}")
OUT=$(realpath -m "${3:?usage: oracle_gap.sh WEATHERGS_BINARY DATASET OUT_DIR}")
for need in dataset.json clean masks sparse/0 sparse_clean/0; do
  [ -e "$DATA/$need" ] || { echo "oracle_gap.sh: $DATA/$need: missing (a generated dataset with clean views, masks and both SfM models is needed)" >&2; exit 2; }
done
mkdir -p "$OUT"
fail() { echo "oracle_gap.sh: $1 failed: $OUT/$1.log" >&2; exit 1; }
reconstruct() {  # NAME METHOD
  [ -f "$OUT/$1/results.json" ] && return 0
  echo "== $(date -Is) $1"
  "$W" --quiet --threads 1 reconstruct --data "$DATA" --method "$2" --seed 0 --out "$OUT/$1" > "$OUT/$1.log" 2>&1 || fail "$1"
}
train() {  # NAME [train flags]
  local name=$1; shift
  [ -f "$OUT/$name/results.json" ] && return 0
  echo "== $(date -Is) $name"
  mkdir -p "$OUT/$name"
  local resume=(); [ -f "$OUT/$name/model/checkpoint.bin" ] && resume=(--resume)
  { "$W" --quiet --threads 1 train --data "$DATA" --seed 0 --out "$OUT/$name/model" "${resume[@]}" "$@" &&
    "$W" --quiet render --model "$OUT/$name/model" --data "$DATA" --split test --method "$name" --out "$OUT/$name/renders" &&
    "$W" --quiet evaluate --gt "$DATA" --renders "$OUT/$name/renders" --method "$name" -o "$OUT/$name/results.json"; } \
    > "$OUT/$name.log" 2>&1 || fail "$name"
}
case "${CELLS:-all}" in
  all|a) reconstruct gt-masks gt-masks; train gt-masks-cleanpts --masks all --points-dir "$DATA/sparse_clean/0" ;;&
  all|b) train clean-weatherpts --images-dir "$DATA/clean"; reconstruct oracle oracle ;;
esac
[ "${CELLS:-all}" = all ] || exit 0
echo "| images | SfM points | run | PSNR / SSIM / LPIPS | Gaussians |"
echo "|---|---|---|---|---|"
for row in "weathered + true masks|weathered views|gt-masks" "weathered + true masks|clean views|gt-masks-cleanpts" \
           "clean|weathered views|clean-weatherpts" "clean|clean views|oracle"; do
  IFS='|' read -r images points name <<<"$row"
  /usr/bin/python3 - "$OUT/$name" "$images" "$points" "$name" <<'PY'
import json, os, sys
run, images, points, name = sys.argv[1:]
r = json.load(open(os.path.join(run, "results.json")))
m = r["metrics"]
n = r.get("method_info", {}).get("num_gaussians")
if n is None:
    n = json.load(open(os.path.join(run, "model", "run.json")))["num_gaussians"]
print(f"| {images} | {points} | {name} | {m['psnr']:.2f} / {m['ssim']:.3f} / {m['lpips']:.3f} | {n} |")
PY
done
