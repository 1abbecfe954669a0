#!/usr/bin/env bash
# Calibrates the peak rule `weathergs detect --adapt` uses (adapted_peak_rule in the LED's weights;
# docs/record/led_adaptation.md, "A rule for adapted maps"): runs `detect --adapt --save-attention`
# on every dataset of HELD_OUT (<scene>_wNN; by default the validation scenes of `make
# validation-data`), then `calibrate-led --maps ... --adapted --peak --min-precision MIN_PRECISION`,
# which writes the same network with that rule added. `make adapted-led-rule`.
#
#   scripts/calibrate-adapted-led.sh WEATHERGS HELD_OUT MAPS WEIGHTS_STEM [OUT_STEM]
#
# MAPS caches the detect outputs (a finished one is kept; delete it to redo it). Each detect runs on
# one thread, JOBS (default 2) at a time; the maps depend neither on how many run at once nor on the
# thread count. About 60 s per dataset on one core (100 adaptation iterations), ~13 min for the 24
# validation datasets on 2 cores. MIN_PRECISION (default 0.8, the precision target; "none" for the
# plain highest mean IoU).
set -euo pipefail
usage="usage: calibrate-adapted-led.sh WEATHERGS HELD_OUT MAPS WEIGHTS_STEM [OUT_STEM]"
BIN=${1:?$usage}
HELD=${2:?$usage}
MAPS=${3:?$usage}
WEIGHTS=${4:?$usage}
OUT=${5:-$WEIGHTS}
JOBS=${JOBS:-2}
MIN_PRECISION=${MIN_PRECISION:-0.8}
[ -f "$WEIGHTS.json" ] || { echo "calibrate-adapted-led: $WEIGHTS.json missing (a weights stem, e.g. models/led/led)" >&2; exit 2; }
shopt -s nullglob
datasets=("$HELD"/*_w[0-9][0-9])
[ ${#datasets[@]} -gt 0 ] || { echo "calibrate-adapted-led: no <scene>_wNN datasets in $HELD (make validation-data)" >&2; exit 2; }
mkdir -p "$MAPS"
export BIN MAPS WEIGHTS
# shellcheck disable=SC2016
printf '%s\n' "${datasets[@]}" | xargs -P "$JOBS" -I{} bash -c '
  d={}; n=$(basename "$d")
  [ -f "$MAPS/$n/detect.json" ] && exit 0
  start=$(date +%s)
  "$BIN" --quiet --threads 1 detect --data "$d" --out "$MAPS/$n" --weights "$WEIGHTS" --adapt --save-attention > /dev/null
  echo "calibrate-adapted-led: $n adapted in $(( $(date +%s) - start )) s"'
maps=()
for d in "${datasets[@]}"; do maps+=("$MAPS/$(basename "$d")"); done
bound=()
[ "$MIN_PRECISION" = none ] || bound=(--min-precision "$MIN_PRECISION")
"$BIN" calibrate-led --weights "$WEIGHTS" --maps "${maps[@]}" --adapted --peak "${bound[@]}" --out "$OUT"
