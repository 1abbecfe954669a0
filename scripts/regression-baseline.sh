#!/usr/bin/env bash
# Regenerates CI's regression baseline (benchmarks/baselines/regression/, README.md there) for the
# current recipes: WeatherGS on the committed fixture for seeds 0..N-1, the tolerances from their
# spread (max(3 x sample std, 1.5 x range), per metric, for the means and per view), and the margins by
# which the injected regressions (the LED masking nothing: weathergs-no-led; the AEF passing its images
# through: weathergs-no-aef; both replaced by plain 3DGS: 3dgs) fall below it, in spreads. Rerun it
# after any change of a default that moves the numbers; it refuses to write a baseline that cannot
# tell those regressions from noise (each must be worse by more than 3 spreads on some metric).
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
commit=$(git -C "$ROOT" rev-parse --short HEAD)
git -C "$ROOT" diff --quiet HEAD -- . 2>/dev/null || commit="$commit with uncommitted changes"
/usr/bin/python3 - "$WORK" "$SEEDS" "$BASE" "$commit" "$REGRESSION_FLAGS" <<'EOF'
import json, math, shutil, statistics, sys
work, seeds, base, commit, flags = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5]
runs = [json.load(open(f"{work}/weathergs_seed{s}/results.json")) for s in range(seeds)]
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
for variant in ["weathergs-no-led", "weathergs-no-aef", "3dgs"]:
    v = json.load(open(f"{work}/{variant}_seed0/results.json"))["metrics"]
    worse = {m: ((b0[m] - v[m]) if higher[m] else (v[m] - b0[m])) for m in metrics}
    in_sd = {m: worse[m] / mean_sd[m] if mean_sd[m] > 0 else math.inf for m in metrics}
    fails = {m: worse[m] > mean_tol[m] for m in metrics}
    margins[variant] = {m: {"worse_by": round(worse[m], 5), "spreads": round(in_sd[m], 2), "fails": fails[m]} for m in metrics}
    if not any(fails[m] and in_sd[m] > 3 for m in metrics):
        ok = False
tolerances = {
    "psnr": round(mean_tol["psnr"], 4), "ssim": round(mean_tol["ssim"], 5), "lpips": round(mean_tol["lpips"], 5),
    "per_view": {m: round(view_tol[m], 5 if m != "psnr" else 4) for m in metrics},
    "basis": (f"max(3 x sample std, 1.5 x range) over WeatherGS seeds 0-{seeds - 1} on "
              f"tests/data/regression/station_rain (reconstruct {flags.strip()}), commit {commit}: " + "; ".join(lines) +
              ". Per view: the same rule per view, the largest over the views."),
}
report = {"seeds": seeds, "commit": commit, "flags": flags.strip(), "tolerances": tolerances,
          "weathergs": [r["metrics"] for r in runs], "injected_regressions": margins, "discriminates": ok}
print(json.dumps(report, indent=2))
if not ok:
    sys.exit("regression-baseline: an injected regression is not worse by more than 3 spreads on any metric; "
             "the baseline was not written")
shutil.copy(f"{work}/weathergs_seed0/results.json", f"{base}/station_rain_weathergs_seed0.json")
json.dump(tolerances, open(f"{base}/tolerances.json", "w"), indent=2)
open(f"{base}/tolerances.json", "a").write("\n")
json.dump(report, open(f"{base}/spread.json", "w"), indent=2)
open(f"{base}/spread.json", "a").write("\n")
print(f"wrote {base}/station_rain_weathergs_seed0.json, tolerances.json, spread.json")
EOF
