#!/usr/bin/env bash
# Runs every libFuzzer harness of a fuzz build for SECONDS each (default 60; the full runs: 600),
# one after the other, seeds from fuzz/corpus/<name>/, new inputs in BUILD/corpus/<name>/, crashes in
# BUILD/crashes/. Prints one line per harness: executions, coverage, and the outcome.
# Usage: fuzz/run.sh BUILD [SECONDS] [harness...]
set -uo pipefail
BUILD=$(readlink -f "$1"); SECONDS_EACH=${2:-60}; shift 2 || true
SRC=$(cd "$(dirname "$0")/.." && pwd)
harnesses=("$@")
[ ${#harnesses[@]} -eq 0 ] && harnesses=(dataset weather_spec scene_spec ply colmap results image)
mkdir -p "$BUILD/crashes"
status=0
for h in "${harnesses[@]}"; do
  exe="$BUILD/fuzz/fuzz_$h"
  [ -x "$exe" ] || { echo "fuzz_$h: not built"; status=1; continue; }
  mkdir -p "$BUILD/corpus/$h"
  log="$BUILD/fuzz_$h.log"
  ASAN_OPTIONS=detect_leaks=1:fast_unwind_on_malloc=0:quarantine_size_mb=64 LSAN_OPTIONS=suppressions=$SRC/tests/lsan.supp "$exe" "$BUILD/corpus/$h" "$SRC/fuzz/corpus/$h" -max_total_time="$SECONDS_EACH" \
    -rss_limit_mb=3072 -timeout=10 -max_len=65536 -artifact_prefix="$BUILD/crashes/$h-" -print_final_stats=1 \
    > "$log" 2>&1
  rc=$?
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$')
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1)
  if [ $rc -eq 0 ]; then echo "fuzz_$h: ${execs:-?} executions, $cov, no crash, hang, leak or sanitizer report";
  else echo "fuzz_$h: FAILED (exit $rc) after ${execs:-?} executions: see $log and $BUILD/crashes/"; status=1; fi
done
exit $status
