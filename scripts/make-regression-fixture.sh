#!/usr/bin/env bash
# Makes the regression fixtures of CI (benchmarks/baselines/README.md), from the held-out training
# scene `station` (never a benchmark scene) at a small size:
#   OUT/station_rain  heavy paper-style rain with drops on the lens, so that the AEF and the LED each
#                     matter; a fixed sparse/0 triangulated once from the clean views (COLMAP is out
#                     of the loop in CI, and every method starts from the same points: the weathered
#                     views of this small size give COLMAP only a handful);
#                     dataset.json, cameras.json, images/, clean/, masks/lens/, sparse/0/
#   OUT/station_snow  four views in heavy snow (the snowy variant's surfaces): images/, clean/
# The shipped networks are tested on them too (tests/restoration/shipped_weights_test.cc).
# Usage: scripts/make-regression-fixture.sh WEATHERGS_BINARY [OUT]   (default tests/data/regression)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BIN=$(realpath "${1:?usage: make-regression-fixture.sh WEATHERGS_BINARY [OUT]}")
OUT=$(realpath -m "${2:-$ROOT/tests/data/regression}")
WORK=$(mktemp -d /tmp/weathergs-fixture.XXXXXX)
trap 'rm -rf "$WORK"' EXIT
PROFILE=${FIXTURE_PROFILE:-fixture}
WIDTH=${FIXTURE_WIDTH:-240}
HEIGHT=${FIXTURE_HEIGHT:-160}
VIEWS=${FIXTURE_VIEWS:-20}

# The scene with a profile of the fixture's size (the scene file itself stays as it is).
/usr/bin/python3 - "$ROOT/scenes/training/station.json" "$WORK/station.json" "$PROFILE" "$WIDTH" "$HEIGHT" "$VIEWS" <<'EOF'
import json, sys
src, dst, name, w, h, views = sys.argv[1:]
scene = json.load(open(src))
scene["profiles"][name] = {"width": int(w), "height": int(h), "views": int(views), "samples": 8}
scene["profiles"][name + "_small"] = {"width": int(w), "height": int(h), "views": 4, "samples": 8}
# Every fourth view held out: five test views, so that one view's luck moves the mean less.
scene["split"] = {"rule": "llff", "every": 4}
json.dump(scene, open(dst, "w"), indent=1)
EOF
cat > "$WORK/snow.json" <<'EOF'
{"seed": 12, "style": "paper", "effects": {"snow": {"intensity": "heavy", "wind_m_s": [0.5, 0.0, 0.0]}}}
EOF
cat > "$WORK/rain.json" <<'EOF'
{"seed": 11, "style": "paper", "effects": {
  "rain": {"intensity": "heavy", "wind_m_s": [1.0, 0.0, 0.0]},
  "lens_droplets": {"count": 40, "radius_mm": [0.8, 2.5], "glass_distance_m": 0.015}}}
EOF
echo "== render station ($PROFILE: ${WIDTH}x${HEIGHT}, $VIEWS views, the wet variant's surfaces and light)"
"$BIN" --quiet generate --scene "$WORK/station.json" --weather wet --profile "$PROFILE" --no-colmap \
  --cache "$WORK/cache" --out "$WORK/clear"
echo "== weather: $(tr -d '\n ' < "$WORK/rain.json")"
"$BIN" --quiet weather --in "$WORK/clear" --spec "$WORK/rain.json" --out "$WORK/rain" --no-manifest --no-layers
echo "== triangulate the clean views (COLMAP, known poses), once"
"$BIN" --quiet triangulate --data "$WORK/rain" --images clean --views all
mkdir -p "$WORK/rain/sparse"
rm -rf "$WORK/rain/sparse/0"
cp -r "$WORK/rain/sparse_clean/0" "$WORK/rain/sparse/0"
echo "== render station, snowy variant, 4 views; weather: $(tr -d '\n ' < "$WORK/snow.json")"
"$BIN" --quiet generate --scene "$WORK/station.json" --weather snowy --profile "${PROFILE}_small" --no-colmap \
  --cache "$WORK/cache" --out "$WORK/clear_snowy"
"$BIN" --quiet weather --in "$WORK/clear_snowy" --spec "$WORK/snow.json" --out "$WORK/snow" --no-manifest --no-layers
copy() {  # from to folders...
  local from=$1 to=$2; shift 2
  rm -rf "$to"
  mkdir -p "$to"
  cp "$from/dataset.json" "$from/cameras.json" "$to/"
  for d in "$@"; do mkdir -p "$(dirname "$to/$d")"; cp -r "$from/$d" "$to/$d"; done
}
copy "$WORK/rain" "$OUT/station_rain" images clean masks/lens sparse/0
copy "$WORK/snow" "$OUT/station_snow" images clean
echo "wrote $OUT: station_rain ($(du -sh "$OUT/station_rain" | cut -f1), $(ls "$OUT/station_rain/images" | wc -l) views)," \
  "station_snow ($(du -sh "$OUT/station_snow" | cut -f1))"
