#!/usr/bin/env bash
# The regression check of CI (benchmarks/baselines/README.md): WeatherGS on the committed fixture
# (tests/data/regression/station_rain: rain and lens drops, a fixed sparse/0, so no Blender and no
# COLMAP), in the declared cell of scripts/regression-cell.env, then `weathergs check` against the
# committed baseline with the tolerances its seed spread set. Exit 1 with a per-metric, per-view
# report when WeatherGS got worse; exit 2 when the run is not comparable (other weights, another
# recipe or form of the cell, another ground truth).
# Usage: scripts/check_baseline.sh [WEATHERGS_BINARY] [WORK_DIR] [METHOD] [CHECK_FLAGS...]
#   WORK_DIR is removed first. METHOD (default weathergs) lets a test inject a regression: another
#   method's run checked against WeatherGS's baseline (with --allow-other-recipe) must fail.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
WGS=$(realpath "${1:-$ROOT/build/apps/weathergs}")
WORK=$(realpath -m "${2:-$ROOT/out/check_baseline}")
METHOD=${3:-weathergs}
shift $(( $# < 3 ? $# : 3 ))
FIXTURE="$ROOT/tests/data/regression/station_rain"
BASE="$ROOT/benchmarks/baselines/regression"
# shellcheck source=/dev/null
source "$ROOT/scripts/regression-cell.env"
SEED=${BASELINE_SEED:-0}
rm -rf "$WORK"
echo "check_baseline: station_rain fixture -> $METHOD (the default schedule $REGRESSION_SCHEDULE shortened:" \
  "$REGRESSION_FLAGS, seed $SEED); baseline $BASE"
# shellcheck disable=SC2086
"$WGS" --quiet reconstruct --data "$FIXTURE" --method "$METHOD" --seed "$SEED" --out "$WORK/run" $REGRESSION_FLAGS
"$WGS" check --baseline "$BASE/station_rain_weathergs_seed0.json" --results "$WORK/run/results.json" \
  --tolerances "$BASE/tolerances.json" --json "$WORK/check.json" "$@"
