#!/usr/bin/env bash
# Regenerates CI's regression baseline (benchmarks/baselines/regression/, README.md there) for the
# current recipes: WeatherGS on the committed fixture for seeds 0..N-1, in the declared cell of
# scripts/regression-cell.env, the tolerances from their spread (max(3 x sample std, 1.5 x range), per
# metric, for the means and per view), and the margins by which the injected regressions (the LED
# masking nothing: weathergs-no-led; the AEF passing its images through: weathergs-no-aef; both
# replaced by plain 3DGS: 3dgs) fall below it, in tolerances and in spreads. Rerun it after any change
# of a default that moves the numbers. It refuses to write a baseline whose runs are not the declared
# form (the default schedule REGRESSION_SCHEDULE, REGRESSION_ITERATIONS long), or that cannot tell
# those regressions from noise (each must be worse by at least REGRESSION_MIN_MARGIN tolerances on
# some metric).
# Usage: scripts/regression-baseline.sh WEATHERGS_BINARY [SEEDS]   (SEEDS default 5, at least 5)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BIN=$(realpath "${1:?usage: regression-baseline.sh WEATHERGS_BINARY [SEEDS]}")
SEEDS=${2:-5}
if [ "$SEEDS" -lt 5 ]; then echo "regression-baseline: at least 5 seeds set a spread" >&2; exit 2; fi
FIXTURE="$ROOT/tests/data/regression/station_rain"
BASE="$ROOT/benchmarks/baselines/regression"
# shellcheck source=/dev/null
source "$ROOT/scripts/regression-cell.env"
WORK=${WORK:-$(mktemp -d /tmp/weathergs-baseline.XXXXXX)}
mkdir -p "$WORK" "$BASE"
"$BIN" --quiet doctor --need lpips,led,aef
run() {  # method seed
  local out="$WORK/$1_seed$2"
  [ -f "$out/results.json" ] && return 0
  echo "== $1, seed $2"
  "$BIN" --quiet --threads "${THREADS:-2}" reconstruct --data "$FIXTURE" --method "$1" --seed "$2" --out "$out" \
    $REGRESSION_FLAGS
}
for s in $(seq 0 $((SEEDS - 1))); do run weathergs "$s"; done
for m in weathergs-no-led weathergs-no-aef 3dgs; do run "$m" 0; done
# The build that made the runs, as the binary names it (commit, "-dirty" for uncommitted changes).
commit=$("$BIN" --version | sed -n 's/.*(\(.*\)).*/\1/p')
/usr/bin/python3 - "$WORK" "$SEEDS" "$BASE" "$commit" "$REGRESSION_FLAGS" "$REGRESSION_SCHEDULE" \
  "$REGRESSION_ITERATIONS" "$REGRESSION_MIN_MARGIN" <<'EOF'
import json, math, shutil, statistics, sys
work, seeds, base, commit, flags = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5]
schedule, iterations, min_margin = sys.argv[6], int(sys.argv[7]), float(sys.argv[8])
variants = ["weathergs-no-led", "weathergs-no-aef", "3dgs"]
runs = [json.load(open(f"{work}/weathergs_seed{s}/results.json")) for s in range(seeds)]
injected = {v: json.load(open(f"{work}/{v}_seed0/results.json")) for v in variants}
# Every run must be the declared cell: the default schedule, shortened to the declared length.
for name, r in [(f"weathergs_seed{s}", r) for s, r in enumerate(runs)] + [(f"{v}_seed0", r) for v, r in injected.items()]:
    info = r["method_info"]
    got = (info.get("schedule"), info.get("iterations"), info.get("schedule_length"))
    if got[0] != schedule or got[1] != iterations or not isinstance(got[2], int) or got[2] < iterations:
        sys.exit(f"regression-baseline: {work}/{name}/results.json records schedule {got[0]}, iterations {got[1]}, "
                 f"schedule_length {got[2]}; the declared cell (scripts/regression-cell.env) is the default schedule "
                 f"{schedule} shortened to {iterations} iterations. Update the declaration if the default changed.")
schedule_length = runs[0]["method_info"]["schedule_length"]
short = iterations < schedule_length
cell = {"method": "weathergs", "schedule": schedule, "iterations": iterations, "schedule_length": schedule_length,
        "form": "a short form of the default recipe" if short else "the default recipe", "flags": flags.strip()}
form = (f"the default schedule {schedule} shortened to {iterations} of its {schedule_length} iterations" if short
        else f"the default schedule {schedule} at its own length, {iterations} iterations")
metrics = ["psnr", "ssim", "lpips"]
higher = {"psnr": True, "ssim": True, "lpips": False}
def spread(xs):
    return statistics.stdev(xs), max(xs) - min(xs)
def tol(xs):
    sd, rg = spread(xs)
    return max(3 * sd, 1.5 * rg), sd
mean_tol, mean_sd = {}, {}
for m in metrics:
    mean_tol[m], mean_sd[m] = tol([r["metrics"][m] for r in runs])
views = list(runs[0]["per_view"])
view_tol = {m: max(tol([r["per_view"][v][m] for r in runs])[0] for v in views) for m in metrics}
lines = []
for m in metrics:
    vals = " / ".join(f"{r['metrics'][m]:.4f}" for r in runs)
    lines.append(f"{m.upper()} {vals} (std {mean_sd[m]:.4f})")
margins, ok = {}, True
b0 = runs[0]["metrics"]
for variant in variants:
    v = injected[variant]["metrics"]
    worse = {m: ((b0[m] - v[m]) if higher[m] else (v[m] - b0[m])) for m in metrics}
    in_sd = {m: worse[m] / mean_sd[m] if mean_sd[m] > 0 else math.inf for m in metrics}
    in_tol = {m: worse[m] / mean_tol[m] if mean_tol[m] > 0 else math.inf for m in metrics}
    fails = {m: worse[m] > mean_tol[m] for m in metrics}
    margins[variant] = {m: {"worse_by": round(worse[m], 5), "tolerances": round(in_tol[m], 2),
                            "spreads": round(in_sd[m], 2), "fails": fails[m]} for m in metrics}
    if not any(in_tol[m] >= min_margin for m in metrics):
        ok = False
tolerances = {
    "psnr": round(mean_tol["psnr"], 4), "ssim": round(mean_tol["ssim"], 5), "lpips": round(mean_tol["lpips"], 5),
    "per_view": {m: round(view_tol[m], 5 if m != "psnr" else 4) for m in metrics},
    "basis": (f"max(3 x sample std, 1.5 x range) over WeatherGS seeds 0-{seeds - 1} on "
              f"tests/data/regression/station_rain, {form} (reconstruct {flags.strip()}), build {commit}: " +
              "; ".join(lines) +
              ". Per view: the same rule per view, the largest over the views."),
}
report = {"seeds": seeds, "commit": commit, "cell": cell, "flags": flags.strip(), "tolerances": tolerances,
          "weathergs": [r["metrics"] for r in runs], "injected_regressions": margins, "min_margin": min_margin,
          "discriminates": ok}
print(json.dumps(report, indent=2))
if not ok:
    sys.exit(f"regression-baseline: an injected regression is not worse by {min_margin:g} tolerances on any metric; "
             "the baseline was not written")
shutil.copy(f"{work}/weathergs_seed0/results.json", f"{base}/station_rain_weathergs_seed0.json")
json.dump(tolerances, open(f"{base}/tolerances.json", "w"), indent=2)
open(f"{base}/tolerances.json", "a").write("\n")
json.dump(report, open(f"{base}/spread.json", "w"), indent=2)
open(f"{base}/spread.json", "a").write("\n")
print(f"wrote {base}/station_rain_weathergs_seed0.json, tolerances.json, spread.json")
EOF
