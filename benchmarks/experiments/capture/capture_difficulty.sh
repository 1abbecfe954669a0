#!/usr/bin/env bash
# How adverse is the benchmark? For every variant of a generated suite (weathergs generate --suite):
#   - mean weathered-vs-clean PSNR of the views, with everything (images/) and with the particles only
#     (the same resolved spec without lens_droplets, re-weathered from the dataset's clean views);
#   - particle and lens mask coverage;
#   - optionally (ITERATIONS > 0) vanilla 3DGS trained on the weathered images and on the clean ones
#     (the oracle), same iterations and seed, scored on the test views against clean.
# Usage: capture_difficulty.sh WEATHERGS SUITE_DIR [ITERATIONS] > table.md
# Numbers go to docs/scenes.md ("How adverse the benchmark is").
set -euo pipefail
WGS=$(readlink -f "$1")
SUITE=$(readlink -f "$2")
ITER=${3:-0}
PY=/usr/bin/python3
WORK=$SUITE/_difficulty
mkdir -p "$WORK"

psnr_table() {  # dataset folder, image folder -> "mean_psnr particle% lens%"
  "$PY" - "$1" "$2" <<'EOF'
import glob, os, sys
import numpy as np
from skimage.io import imread
root, sub = sys.argv[1], sys.argv[2]
def psnr(a, b):
    mse = np.mean((a.astype(np.float64) - b.astype(np.float64)) ** 2) / 255.0 ** 2
    return 10 * np.log10(1 / mse) if mse > 0 else float("inf")
vals = [psnr(imread(f)[..., :3], imread(f"{root}/clean/{os.path.basename(f)}")[..., :3])
        for f in sorted(glob.glob(f"{root}/{sub}/*.png"))]
cov = {}
for m in ("particles", "lens"):
    fs = sorted(glob.glob(f"{root}/masks/{m}/*.png"))
    cov[m] = f"{100 * np.mean([(imread(f) > 127).mean() for f in fs]):.1f}%" if fs else "-"
print(f"{np.mean(vals):.2f} {cov['particles']} {cov['lens']}")
EOF
}

train_psnr() {  # dataset, run name, extra train flags -> test PSNR
  local run="$WORK/runs/$2"
  "$WGS" --quiet train --data "$1" --out "$run" --iterations "$ITER" --seed 1 --force $3 >/dev/null
  "$WGS" --quiet render --model "$run" --out "$run.renders" >/dev/null
  "$WGS" --quiet evaluate --gt "$1" --renders "$run.renders" --method x --no-lpips -o "$run.json" >/dev/null
  "$PY" -c "import json,sys; print(f\"{json.load(open(sys.argv[1]))['metrics']['psnr']:.2f}\")" "$run.json"
}

echo "| variant | style | weathered vs clean | particles only | particle mask | lens mask | 3DGS weathered | 3DGS particles only | 3DGS oracle | gap | gap (particles only) |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
for ds in "$SUITE"/*/; do
  ds=${ds%/}
  name=$(basename "$ds")
  [ -f "$ds/dataset.json" ] || continue
  style=$("$PY" -c "import json,sys; print(json.load(open(sys.argv[1]))['generator']['spec'].get('style','physical'))" "$ds/dataset.json")
  read -r all pmask lmask < <(psnr_table "$ds" images)
  # Particles only: the resolved spec without lens drops, applied to the same clean views.
  "$PY" - "$ds/dataset.json" "$WORK/$name.particles.json" <<'EOF'
import json, sys
spec = json.load(open(sys.argv[1]))["generator"]["spec"]
spec["effects"].pop("lens_droplets", None)
json.dump(spec, open(sys.argv[2], "w"))
EOF
  only="$all"; onlyds="$ds"
  if "$PY" -c "import json,sys; sys.exit(0 if 'lens_droplets' in json.load(open(sys.argv[1]))['generator']['spec']['effects'] else 1)" "$ds/dataset.json"; then
    onlyds="$WORK/$name.particles"
    "$WGS" --quiet weather --in "$ds" --spec "$WORK/$name.particles.json" --out "$onlyds" --no-manifest >/dev/null
    read -r only _ _ < <(psnr_table "$onlyds" images)
  fi
  g_w="-"; g_p="-"; g_o="-"; gap="-"; gap_p="-"
  if [ "$ITER" -gt 0 ]; then
    g_w=$(train_psnr "$ds" "$name.weathered" "")
    g_o=$(train_psnr "$ds" "$name.oracle" "--images clean")
    gap=$("$PY" -c "print(f'{$g_o - $g_w:.2f}')")
    if [ "$onlyds" != "$ds" ]; then
      g_p=$(train_psnr "$onlyds" "$name.particles" "")
      gap_p=$("$PY" -c "print(f'{$g_o - $g_p:.2f}')")
    fi
  fi
  echo "| $name | $style | $all dB | $only dB | $pmask | $lmask | $g_w | $g_p | $g_o | $gap | $gap_p |"
done
