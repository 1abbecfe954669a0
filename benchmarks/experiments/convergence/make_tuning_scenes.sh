#!/usr/bin/env bash
# The tuning scenes of the convergence study: station and village (held-out training scenes, never
# benchmark scenes), quick profile, with the benchmark's paper-style heavy rain with lens drops and
# heavy snow (the weather of pool's variants). Settings are chosen on these; the benchmark cells are
# read once afterwards.
# Usage: [SCENES="village"] [WEATHERS="rain"] make_tuning_scenes.sh WEATHERGS_BINARY OUT_DIR [CACHE_DIR]
# Writes OUT_DIR/{station,village}_{rain,snow}/ with sparse/0 (weathered views) and sparse_clean/0.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../../.." && pwd)
W=$(realpath "${1:?usage: make_tuning_scenes.sh WEATHERGS_BINARY OUT_DIR [CACHE_DIR]}")
OUT=$(realpath -m "${2:?usage: make_tuning_scenes.sh WEATHERGS_BINARY OUT_DIR [CACHE_DIR]}")
CACHE=$(realpath -m "${3:-$OUT/cache}")
mkdir -p "$OUT"
cat > "$OUT/rain.json" <<'J'
{"seed": 7, "style": "paper", "effects": {"rain": {"intensity": "heavy", "wind_m_s": [1.0, 0.0, 0.0]},
 "lens_droplets": {"count": 20, "radius_mm": [0.3, 1.5], "glass_distance_m": 0.015}}}
J
cat > "$OUT/snow.json" <<'J'
{"seed": 7, "style": "paper", "effects": {"snow": {"intensity": "heavy", "wind_m_s": [0.5, 0.0, 0.0]}}}
J
for scene in ${SCENES:-station village}; do
  for v in wet:rain snowy:snow; do
    variant=${v%%:*}; weather=${v##*:}
    [[ " ${WEATHERS:-rain snow} " == *" $weather "* ]] || continue
    [ -f "$OUT/${scene}_${weather}/dataset.json" ] && continue
    [ -f "$OUT/clear_${scene}_${variant}/dataset.json" ] ||
      "$W" --quiet --threads 1 generate --scene "$ROOT/scenes/training/$scene.json" --weather "$variant" \
        --profile quick --no-colmap --cache "$CACHE" --out "$OUT/clear_${scene}_${variant}"
    "$W" --quiet weather --in "$OUT/clear_${scene}_${variant}" --spec "$OUT/$weather.json" --out "$OUT/${scene}_${weather}"
    "$W" --quiet --threads 1 triangulate --data "$OUT/${scene}_${weather}" --images images --views all
    "$W" --quiet --threads 1 triangulate --data "$OUT/${scene}_${weather}" --images clean --views all
  done
done
