#!/usr/bin/env bash
# Does the benchmark's verdict carry over to layouts and optics it was not made on? Two randomized
# street layouts (scripts/make-assorted-scenes.py with seed 2: no network trained or was calibrated on
# them; the shipped weights saw seed 1's) at the quick profile, rendered by Cycles like the benchmark,
# each with other camera optics than the benchmark's f/2.8 focused at 2 m, and the benchmark's heavy
# paper-style rain with 20 lens drops (pool's rain spec). Runs 3dgs, weathergs, gt-masks and oracle at
# the default schedule, one thread each, two at a time, and prints per layout: each method's test
# PSNR / SSIM / LPIPS, WeatherGS's gain over 3DGS, its share of the oracle's gap, the LED's IoU and
# precision against the true drops, and whether the silent-LED warning fired.
# Usage: [DATA_ONLY=1] [JOBS=2] [ARCHIVE=DIR] [BENCH_RUNS=DIR] carryover.sh WEATHERGS_BINARY OUT_DIR
# Resumable: finished datasets and runs are kept. DATA_ONLY=1 stops after the datasets; JOBS: runs at a
# time; ARCHIVE: the results archive whose rain variants the layouts are set beside (the quick suite's);
# BENCH_RUNS: the workflow's runs folder of those cells, for the benchmark's LED scores (optional).
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../../.." && pwd)
W=$(realpath "${1:?usage: carryover.sh WEATHERGS_BINARY OUT_DIR}")
OUT=$(realpath -m "${2:?usage: carryover.sh WEATHERGS_BINARY OUT_DIR}")
mkdir -p "$OUT/specs" "$OUT/data" "$OUT/runs"
/usr/bin/python3 "$ROOT/scripts/make-assorted-scenes.py" 2 "$OUT/specs/assorted" 2 >/dev/null
# name:index:f_number:focus_distance_m. Wide open focused near (drops larger and softer), stopped down
# focused far (drops smaller and sharper).
LAYOUTS="carry_a:00:1.8:1.0 carry_b:01:8.0:10.0"
for l in $LAYOUTS; do
  IFS=: read -r name index fnum focus <<<"$l"
  /usr/bin/python3 - "$OUT/specs/assorted/assorted_$index.json" "$ROOT/scenes/pool.json" "$OUT/specs/$name.json" \
    "$name" "$fnum" "$focus" <<'PY'
import json, sys
src, pool, dst, name, fnum, focus = sys.argv[1:]
s, p = json.load(open(src)), json.load(open(pool))
s["name"] = name
s["camera"]["f_number"], s["camera"]["focus_distance_m"] = float(fnum), float(focus)
s["profiles"] = p["profiles"]                      # the benchmark's: Cycles, 64 samples at quick
s["variants"]["wet"]["weather"] = p["variants"]["rain"]["weather"]  # heavy paper-style rain, 20 drops
json.dump(s, open(dst, "w"), indent=1)
PY
  [ -f "$OUT/data/${name}_wet/dataset.json" ] ||
    "$W" --quiet --threads 2 generate --scene "$OUT/specs/$name.json" --weather wet --profile quick \
      --cache "$OUT/cache" --out "$OUT/data/${name}_wet"
done
[ "${DATA_ONLY:-0}" = 1 ] && exit 0
cells=()
for l in $LAYOUTS; do for m in 3dgs weathergs gt-masks oracle; do cells+=("${l%%:*}_wet:$m"); done; done
run_cell() {
  local data=${1%%:*} method=${1##*:}
  [ -f "$OUT/runs/$data/$method/results.json" ] ||
    "$W" --quiet --threads 1 reconstruct --data "$OUT/data/$data" --method "$method" --seed 0 \
      --out "$OUT/runs/$data/$method" > "$OUT/runs/$data.$method.log" 2>&1
}
export -f run_cell; export W OUT
printf '%s\n' "${cells[@]}" | xargs -P "${JOBS:-2}" -I{} bash -c 'run_cell {}'
/usr/bin/python3 "$ROOT/benchmarks/experiments/carryover/summary.py" "$OUT" "${ARCHIVE:-$ROOT/benchmarks/results/quick}" \
  "${BENCH_RUNS:-}" $LAYOUTS
