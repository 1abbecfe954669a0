#!/usr/bin/env bash
# The demo behind `make demo`: writes a small synthetic benchmark (two scenes in rain and snow, with
# renders of three toy methods), scores every method on every dataset, and prints the leaderboard.
set -euo pipefail
WGS=${1:-build/apps/weathergs}
OUT=${2:-demo_out}
mkdir -p "$OUT"
"$WGS" --quiet example -o "$OUT/example"
mkdir -p "$OUT/results"
for method_dir in "$OUT"/example/renders/*/; do
  method=$(basename "$method_dir")
  for dataset_dir in "$method_dir"*/; do
    dataset=$(basename "$dataset_dir")
    "$WGS" --quiet evaluate --gt "$OUT/example/datasets/$dataset" --renders "$dataset_dir" \
      -o "$OUT/results/${method}_${dataset}.json" >/dev/null
  done
done
"$WGS" leaderboard "$OUT"/results/*.json --format md
"$WGS" leaderboard "$OUT"/results/*.json --format html -o "$OUT/leaderboard.html"
echo
echo "Results: $OUT/results/*.json   HTML table: $OUT/leaderboard.html"
