#!/usr/bin/env bash
# The demo behind `make demo`: the benchmark's main job, small. Generates the quick profile of pool in
# snow and in rain (Blender + the weather generator + COLMAP), reconstructs each with vanilla 3DGS,
# WeatherGS and the oracle (3DGS on the clean images) through the Snakemake workflow, scores every
# run against the clean ground truth and prints the paper's tables (docs/methods.md).
# Usage: scripts/demo.sh [WEATHERGS_BINARY] [OUT]; DEMO_ITERATIONS overrides the iterations.
set -euo pipefail
WGS=$(realpath "${1:-build/apps/weathergs}")
OUT=$(realpath -m "${2:-demo_out}")
ITERATIONS=${DEMO_ITERATIONS:-1000}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
PROFILE=${DEMO_PROFILE:-quick}
VARIANTS="[pool_snow,pool_rain]"
METHODS="[3dgs,weathergs,oracle]"
# The converged runs of this profile's suite, which the report shows beside the demo's (docs/archive.md).
ARCHIVE="$ROOT/benchmarks/results/$PROFILE"
# What the tables and the report say they are. No single quote in it: it travels YAML-quoted.
NOTE="A smoke run: $ITERATIONS iterations per method, one seed, not converged. These numbers show that every stage\
 runs, not what the methods reach. The converged tables (the fast schedule, every method, seeds) are in docs/results.md,\
 read from the results archive benchmarks/results/$PROFILE."

cat <<EOF
weathergs demo: can 3D reconstruction see through the weather?
  1. generate: Blender renders the procedural 'pool' scene ($PROFILE profile: 16 views of 300x200), the weather generator adds
     falling snow or rain and drops on the lens, COLMAP triangulates SfM points. The clean renders
     are the ground truth.
  2. reconstruct, per variant, with $ITERATIONS iterations each:
       3dgs       vanilla 3D Gaussian Splatting on the weathered images (the paper's baseline)
       weathergs  particle filter (AEF) -> lens-drop detector (LED) -> 3DGS with the drops masked out
       oracle     3DGS on the clean images: the upper bound
  3. score the test views against the clean ground truth (PSNR, SSIM, LPIPS) and print the tables.
A smoke run: $ITERATIONS iterations, where every method's curve is still climbing. The benchmark's
converged tables (the fast schedule, every method, seeds) are in docs/results.md, read from the
committed results archive benchmarks/results/; the report shows the archive's runs of these variants
beside the demo's, in tables of their own.
Workflow: workflow/Snakefile (Snakemake; each line below is tagged with its cell). Output: $OUT
EOF
start=$(date +%s)
cd "$ROOT"
# Everything the demo needs, checked before Blender starts and before $OUT is made.
if [ ! -x "$WGS" ]; then echo "demo: the weathergs binary $WGS does not exist; run 'make build' first" >&2; exit 2; fi
if ! "$WGS" --quiet doctor --need lpips,led,aef,blender,blender-script,colmap,out --out "$OUT"; then
  echo "demo: stopped before any work: a resource above is missing (nothing was written to $OUT)" >&2
  exit 2
fi
mkdir -p "$OUT"
USER=${USER:-weathergs} snakemake -s workflow/Snakefile --directory "$OUT" --cores 2 --config weathergs="$WGS" \
  scenes="$ROOT/scenes" out="$OUT" profile="$PROFILE" iterations="$ITERATIONS" threads=1 \
  "variants=$VARIANTS" "methods=$METHODS" "seeds=[0]" "note='$NOTE'" \
  "converged=$([ -d "$ARCHIVE" ] && echo "$ARCHIVE")"
echo
echo "== A smoke run at $ITERATIONS iterations, not converged: the numbers below show that every stage runs, not"
echo "== what the methods reach. Converged tables: docs/results.md (from the archive benchmarks/results/$PROFILE)."
echo
cat "$OUT/tables.md"
echo "Done in $(( $(date +%s) - start )) s. Tables: $OUT/tables.md (csv: tables.csv), per-scene" \
  "leaderboard: $OUT/leaderboard.html, runs and renders: $OUT/runs/, logs: $OUT/logs/."
echo
echo "The results browser (renders beside the weather and the truth, curves, cost; opens offline):"
echo "  open $OUT/report/index.html"
echo
echo "These are a smoke run ($ITERATIONS iterations, one seed): not converged. The converged quick suite"
echo "(fast schedule, seeds 0-2 for the headline methods, intervals): docs/results.md and benchmarks/results/."
if [ -d "$ARCHIVE" ]; then
  echo "The archive's runs of these variants, beside the demo's (or what it still lacks): the report's page"
  echo "'Converged (archive)', open $OUT/report/index.html#converged"
fi
