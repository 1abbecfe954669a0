#!/usr/bin/env bash
# The regression check of CI (docs/study.md, "Baseline"): the cheapest cell of `make demo` (pool in
# rain, quick profile, WeatherGS, 1000 iterations, seed 0) generated and reconstructed from scratch,
# then `weathergs check` against the committed demo results with the tolerances the seed spread set
# (benchmarks/baselines/demo/). Exit 1 with a per-metric report when WeatherGS got worse.
# Usage: scripts/check_baseline.sh [WEATHERGS_BINARY] [WORK_DIR]   (WORK_DIR is removed first)
# Exit 77 (ctest: skipped) when Blender or COLMAP is missing.
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
WGS=$(realpath "${1:-$ROOT/build/apps/weathergs}")
WORK=$(realpath -m "${2:-$ROOT/out/check_baseline}")
BASE="$ROOT/benchmarks/baselines/demo"
SEED=${BASELINE_SEED:-0}
for tool in blender colmap; do
  if ! command -v "$tool" > /dev/null; then echo "check_baseline: $tool is not installed: skipped"; exit 77; fi
done
rm -rf "$WORK"
mkdir -p "$WORK"
echo "check_baseline: pool_rain (quick) -> weathergs, 1000 iterations, seed $SEED; baseline $BASE"
"$WGS" --quiet generate --scene "$ROOT/scenes/pool.json" --weather rain --profile quick --targets \
  --cache "$WORK/cache" --out "$WORK/pool_rain"
"$WGS" --quiet reconstruct --data "$WORK/pool_rain" --method weathergs --iterations 1000 --seed "$SEED" \
  --out "$WORK/run"
"$WGS" check --baseline "$BASE/pool_rain_weathergs_seed0.json" --results "$WORK/run/results.json" \
  --tolerances "$BASE/tolerances.json" --json "$WORK/check.json"
