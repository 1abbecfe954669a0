#!/usr/bin/env bash
# CI's regression check can fail: each injected regression, run on the fixture and checked against
# WeatherGS's baseline, must exit 1 (benchmarks/baselines/README.md):
#   weathergs-no-led  the LED masking nothing
#   weathergs-no-aef  the AEF passing its images through
#   3dgs              both replaced by plain 3DGS
set -u
wgs="$1"; work="$2"; src="$3"
fail=0
for method in weathergs-no-led weathergs-no-aef 3dgs; do
  bash "$src/scripts/check_baseline.sh" "$wgs" "$work/$method" "$method" --allow-other-recipe --allow-other-weights \
    > "$work.$method.log" 2>&1
  rc=$?
  if [ $rc = 1 ]; then
    echo "$method: fails the check, as it must: $(grep -c FAIL "$work.$method.log") failing lines"
  else
    echo "$method: the check exited $rc, expected 1 (a regression the check cannot see)"; cat "$work.$method.log"; fail=1
  fi
done
exit $fail
