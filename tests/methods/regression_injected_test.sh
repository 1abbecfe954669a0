#!/usr/bin/env bash
# CI's regression check can fail: each injected regression, run on the fixture and checked against
# WeatherGS's baseline, must exit 1 (benchmarks/baselines/README.md), and be worse than the baseline by
# at least REGRESSION_MIN_MARGIN tolerances on some metric (scripts/regression-cell.env), so that a
# stage that stops mattering, or a baseline whose tolerances swallow it, fails here:
#   weathergs-no-led  the LED masking nothing
#   weathergs-no-aef  the AEF passing its images through
#   3dgs              both replaced by plain 3DGS
set -u
wgs="$1"; work="$2"; src="$3"
# shellcheck source=/dev/null
source "$src/scripts/regression-cell.env"
fail=0
for method in weathergs-no-led weathergs-no-aef 3dgs; do
  bash "$src/scripts/check_baseline.sh" "$wgs" "$work/$method" "$method" --allow-other-recipe --allow-other-weights \
    > "$work.$method.log" 2>&1
  rc=$?
  if [ $rc != 1 ]; then
    echo "$method: the check exited $rc, expected 1 (a regression the check cannot see)"; cat "$work.$method.log"; fail=1
    continue
  fi
  # The largest margin over the metrics, in tolerances: (how much worse) / (what the check allows).
  margin=$(/usr/bin/python3 - "$work/$method/check.json" <<'EOF'
import json, sys
c = json.load(open(sys.argv[1]))
tol = c["tolerances"]
best = ("none", float("-inf"))
for row in c["datasets"][0]["metrics"]:
    m = row["metric"]
    worse = (row["baseline"] - row["new"]) if m in ("PSNR", "SSIM") else (row["new"] - row["baseline"])
    t = tol[m.lower()]
    r = worse / t if t > 0 else float("inf")
    if r > best[1]:
        best = (m, r)
print(f"{best[1]:.2f} {best[0]}")
EOF
  )
  read -r times metric <<< "$margin"
  if /usr/bin/python3 -c "import sys; sys.exit(0 if float('$times') >= float('$REGRESSION_MIN_MARGIN') else 1)"; then
    echo "$method: fails the check, as it must: $(grep -c FAIL "$work.$method.log") failing lines; worse by" \
      "$times tolerances on $metric (at least $REGRESSION_MIN_MARGIN required)"
  else
    echo "$method: fails the check, but worse by only $times tolerances on $metric, under the" \
      "$REGRESSION_MIN_MARGIN required: the regression is barely told from noise"
    cat "$work.$method.log"; fail=1
  fi
done
exit $fail
