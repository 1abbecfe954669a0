#!/usr/bin/env bash
# Times `weathergs generate --suite scenes/suite.json --profile quick` from an empty cache, then one
# variant again with another weather seed (cache hit). Usage: capture_quick_suite.sh WEATHERGS OUTDIR
set -euo pipefail
bin=$1
out=$2
src=$(cd "$(dirname "$0")/.." && pwd)
rm -rf "$out"
mkdir -p "$out"
echo "== quick suite from an empty cache"
/usr/bin/time -v "$bin" --quiet generate --suite "$src/scenes/suite.json" --profile quick \
  --cache "$out/cache" --out "$out/suite" 2> "$out/time_suite.txt"
grep -E "Elapsed|Maximum resident" "$out/time_suite.txt"
echo "== pool rain again with seed 8 (cached render)"
/usr/bin/time -v "$bin" --quiet generate --scene "$src/scenes/pool.json" --weather rain --profile quick --seed 8 \
  --cache "$out/cache" --out "$out/pool_rain_seed8" 2> "$out/time_cached.txt"
grep -E "Elapsed|Maximum resident" "$out/time_cached.txt"
