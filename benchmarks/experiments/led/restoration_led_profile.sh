#!/usr/bin/env bash
# The LED (the shipped weights, or LED_WEIGHTS=STEM) on the benchmark scenes at one render profile
# (docs/restoration_led.md, "Current numbers": the paper-profile rows). Generates the rain variants of both
# styles and the paper-style snow variants of tanabata, factory and pool at PROFILE (no COLMAP, with
# the restoration targets; the clean renders come from the generate cache, so a second run only
# re-weathers), runs `weathergs detect` on each (the default post-processing: the training views'
# averaged map, the weights' peak rule, three 3x3 dilations) and prints one row per variant: IoU /
# precision / recall against masks/lens pooled over the training views, or, for the drop-free snow
# variants, the share of pixels masked. Existing datasets in OUT are reused.
# Usage: benchmarks/experiments/led/restoration_led_profile.sh WEATHERGS OUT [PROFILE=paper] > table.md
# OUT is laid out like the repository root, so that the drop-layout script reads its suite
# (restoration_led_layouts.py WEATHERGS OUT2 --suite OUT/data/suite_paper): datasets in
# OUT/data/suite_<style>/<scene>_<weather>, masks and averaged maps (--save-attention) of the rain
# variants in OUT/masks/<style>_<scene>, the snow variants' masks in OUT/masks_snow/.
# The paper profile (600x400, 34 views, 29 of them training views) renders each scene in Blender once
# per surface state: ~5-9 min per scene on 2 cores, ~45 min for all six renders.
set -euo pipefail
WGS=$(readlink -f "$1")
OUT=$2
PROFILE=${3:-paper}
HERE=$(cd "$(dirname "$0")/../../.." && pwd)  # the repository root
mkdir -p "$OUT"
echo "| variant | style | IoU / precision / recall | masked | seconds (generate) |"
echo "|---|---|---|---:|---:|"
for style in paper physical; do
  for weather in rain snow; do
    [ "$style" = physical ] && [ "$weather" = snow ] && continue
    for scene in pool tanabata factory; do
      d="$OUT/data/suite_$style/${scene}_$weather"
      m="$OUT/masks/${style}_$scene"
      [ "$weather" = snow ] && m="$OUT/masks_snow/${style}_$scene"
      start=$(date +%s)
      if [ ! -f "$d/dataset.json" ]; then
        "$WGS" --quiet generate --scene "$HERE/scenes/$scene.json" --weather "$weather" --style "$style" \
          --profile "$PROFILE" --no-colmap --targets --out "$d" > /dev/null
      fi
      secs=$(( $(date +%s) - start ))
      "$WGS" --quiet detect --data "$d" --out "$m" --save-attention ${LED_WEIGHTS:+--weights "$LED_WEIGHTS"} > /dev/null
      /usr/bin/python3 - "$m/detect.json" "${scene}_$weather" "$style" "$secs" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1]))
g = r.get("ground_truth")
masked = sum(v["mask_fraction"] for v in r["views"]) / len(r["views"]) * 100
cell = f"{g['iou']:.3f} / {g['precision']:.3f} / {g['recall']:.3f}" if g and g["gt_fraction"] > 0 else "no drops"
print(f"| {sys.argv[2]} | {sys.argv[3]} | {cell} | {masked:.2f} % | {sys.argv[4]} |")
EOF
    done
  done
done
