#!/usr/bin/env bash
# Retrains every weight file this project ships (models/README.md) from the training set of
# scripts/make-training-data.sh: `make models`. Held out, never trained on:
# - LED: one whole training scene (LED_HELD_SCENE, default market): its weathers with drops calibrate
#   the threshold and give the reported metrics, so both are measured on a scene the network never saw
#   (the benchmark's scenes are unseen too); its overcast bases (<scene>_wet_wNN,
#   <scene>_snowy_wNN) are held out with it. The photograph datasets (photo_*_wNN, crop variety:
#   their particles fall on a synthetic depth) and the overcast bases train the LED and nothing else.
#   The randomized assorted scenes (ASSORTED_SCENES in make-training-data.sh) are held out as well:
#   after training, the peak rule is calibrated again on market and them together (`weathergs
#   calibrate-led`; docs/record/led_scenes.md). The LED does not need them before that, so when
#   they are missing from TRAINING_DATA they are made beside its training, once the AEF plugins are
#   done (`TRAINING_PART=assorted scripts/make-training-data.sh`; ASSORTED_SCENES=0 calibrates on
#   market alone).
# - AEF and selector: the last weather of each training scene (*_w11 with the default 12) and the whole
#   market scene, so that the selector's theta and the held-out PSNRs come from a scene the networks
#   never saw.
#
#   scripts/train-models.sh BUILD/apps/weathergs TRAINING_DATA OUT_MODELS_DIR [ITERATIONS]
#   ONLY=led|aef|selector (environment): retrain only those weights (default: all; aef = the two
#   plugins and the selector). LED_SPLIT_ONLY=1 prints the LED's training and held-out datasets
#   (`train PATH`, `held PATH`) and stops.
set -euo pipefail
BIN=${1:?usage: train-models.sh WEATHERGS_BINARY TRAINING_DATA OUT [ITERATIONS]}
DATA=${2:?usage: train-models.sh WEATHERGS_BINARY TRAINING_DATA OUT [ITERATIONS]}
OUT=${3:?usage: train-models.sh WEATHERGS_BINARY TRAINING_DATA OUT [ITERATIONS]}
ITERATIONS=${4:-6000}   # the LED's iterations
LED_WIDTH=${LED_WIDTH:-216}     # the LED's internal width (docs/restoration_led.md)
LED_JITTER=${LED_JITTER:-0}     # its colour jitter (0.25 was tried: docs/record/led_variants.md)
LED_BALANCE=${LED_BALANCE:-0}   # its drop-size balance (--balance-drops; 0 = off)
LED_HELD_SCENE=${LED_HELD_SCENE:-market}
LED_SEED=${LED_SEED:-1}       # its training seed
LED_BATCH=${LED_BATCH:-4}     # its views per iteration
LED_POOLING=${LED_POOLING:-none}  # its --view-pooling (measured, not adopted: docs/record/led_variants.md, "Pooling over the views")
# What the assorted scenes of ASSORTED_SCENES=N (make-training-data.sh) do for the LED: calibrate (held
# out with LED_HELD_SCENE: they calibrate the peak rule and are scored) or train (added to its
# training data); both measured in docs/record/led_scenes.md.
LED_ASSORTED=${LED_ASSORTED:-calibrate}
case $LED_ASSORTED in calibrate | train) ;; *) echo "train-models: LED_ASSORTED must be calibrate or train, not '$LED_ASSORTED'" >&2; exit 2 ;; esac
ONLY=${ONLY:-all}
HERE=$(cd "$(dirname "$0")/.." && pwd)
# Makes the assorted scenes TRAINING_DATA lacks (a no-op when they are there), with the profile and
# weather count the set was made with.
make_assorted() {
  local manifest="$DATA/manifest.json" profile weathers
  if [ ! -f "$manifest" ]; then echo "train-models: $manifest missing: $DATA was not made by scripts/make-training-data.sh" >&2; return 2; fi
  profile=$(grep -o '"profile": "[a-z]*"' "$manifest" | cut -d'"' -f4)
  weathers=$(grep -o '"weathers_per_scene": [0-9]*' "$manifest" | grep -o '[0-9]*$')
  TRAINING_PART=assorted bash "$HERE/scripts/make-training-data.sh" "$BIN" "$DATA" "$weathers" "$profile"
}
if [ -f "$DATA/manifest.json" ] && grep -q '"part": "validation"' "$DATA/manifest.json"; then
  echo "train-models: $DATA holds the validation scenes (TRAINING_PART=validation), which no network trains on" >&2; exit 2
fi
led_runs() { [ "$ONLY" = all ] || [ "$ONLY" = led ]; }
if [ "$LED_ASSORTED" = train ] && led_runs; then make_assorted; fi  # they train: needed first
# Datasets and clear renders that only the LED uses: the photographs, the overcast bases and the
# scenes of EXTRA_SCENES=1 and ASSORTED_SCENES=N (scripts/make-training-data.sh; the assorted ones
# calibrate it by default, LED_ASSORTED below).
led_only() {
  case $1 in photo_* | *_wet | *_snowy | *_wet_w[0-9][0-9] | *_snowy_w[0-9][0-9] | station* | village* | assorted_*) return 0 ;; esac
  return 1
}
train=() held=() held_last=()
for d in "$DATA"/*_w[0-9][0-9]; do
  [ -f "$d/dataset.json" ] || continue
  name=$(basename "$d")
  last=$(ls -d "${d%_w*}"_w[0-9][0-9] | sort | tail -1)
  if ! led_only "$name" && [ "$d" = "$last" ]; then held_last+=("$d"); fi
  base=${name%_w[0-9][0-9]}
  base=${base%_wet}
  base=${base%_snowy}
  if [ "$LED_ASSORTED" = calibrate ] && [[ $name == assorted_* ]]; then
    continue  # listed again for the calibration after training (they may not exist yet)
  elif [ "$base" = "$LED_HELD_SCENE" ]; then
    held+=("$d")
  else
    train+=("$d")
  fi
done
if [ ${#train[@]} -eq 0 ] || [ ${#held[@]} -eq 0 ]; then echo "train-models: no training datasets in $DATA or no scene $LED_HELD_SCENE (run make training-data)" >&2; exit 2; fi
if [ "${LED_SPLIT_ONLY:-0}" = 1 ]; then  # print the LED's split ("train PATH" / "held PATH" lines) and stop (benchmarks/ reuse it)
  printf 'train %s\n' "${train[@]}"
  printf 'held %s\n' "${held[@]}"
  exit 0
fi

# The AEF's training and held-out sets (the clear renders, clear/<scene>, are clear views for the
# plugins and the selector).
AEF_HELD_SCENE=market
AEF_ITERATIONS=${AEF_ITERATIONS:-5000}
SELECTOR_ITERATIONS=${SELECTOR_ITERATIONS:-1500}
aef_train=() aef_held=()
for d in "$DATA"/*_w[0-9][0-9] "$DATA"/clear/*; do
  [ -f "$d/dataset.json" ] || continue
  name=$(basename "$d")
  led_only "$name" && continue
  if [ "${name%_w[0-9][0-9]}" = "$AEF_HELD_SCENE" ] || [[ " ${held_last[*]} " == *" $d "* ]]; then aef_held+=("$d"); else aef_train+=("$d"); fi
done

# Every network trains with one thread (the same seed then gives the same weights), so the work runs
# as two single-threaded jobs side by side, one per core: the LED, and the two AEF plugins, the
# assorted scenes and the selector (their times: docs/restoration.md). Each job logs to
# OUT/logs/<job>.log; the LED's final calibration to OUT/logs/led_calibration.log.
mkdir -p "$OUT/led" "$OUT/aef" "$OUT/logs"
led_job() {
  if led_runs; then
    echo "train-models: LED on ${#train[@]} datasets, calibrated on ${#held[@]} held out"
    "$BIN" --threads 1 train-led --data "${train[@]}" --held-out "${held[@]}" --out "$OUT/led/led" \
      --iterations "$ITERATIONS" --batch "$LED_BATCH" --width "$LED_WIDTH" --colour-jitter "$LED_JITTER" --balance-drops "$LED_BALANCE" --calibrate-peak --seed "$LED_SEED" --view-pooling "$LED_POOLING" --threads 1
  fi
}
aef_job() {  # the longer LED has the other core: this job takes the rest
  if [ "$ONLY" = all ] || [ "$ONLY" = aef ]; then
    echo "train-models: AEF plugins on ${#aef_train[@]} datasets, ${#aef_held[@]} held out (scene $AEF_HELD_SCENE and *_w11)"
    for model in derain desnow; do
      "$BIN" --threads 1 train-aef --model $model --data "${aef_train[@]}" --held-out "${aef_held[@]}" --out "$OUT/aef/$model" \
        --iterations "$AEF_ITERATIONS" --seed 1 --threads 1
    done
  fi
  if [ "$LED_ASSORTED" = calibrate ] && led_runs; then
    echo "train-models: the assorted scenes that calibrate the LED (made unless cached)"
    RENDER_JOBS=1 make_assorted  # one render at a time: the LED trains on the other core
  fi
  if [ "$ONLY" = all ] || [ "$ONLY" = aef ] || [ "$ONLY" = selector ]; then
    echo "train-models: weather selector on ${#aef_train[@]} datasets, theta calibrated on ${#aef_held[@]} held out"
    "$BIN" --threads 1 train-aef --model selector --data "${aef_train[@]}" --held-out "${aef_held[@]}" --out "$OUT/aef/selector" \
      --iterations "$SELECTOR_ITERATIONS" --seed 1 --threads 1
  fi
}
start=$(date +%s)
led_job > "$OUT/logs/led.log" 2>&1 &
led_pid=$!
aef_job > "$OUT/logs/aef.log" 2>&1 &
aef_pid=$!
echo "train-models: two jobs running (logs: $OUT/logs/led.log, $OUT/logs/aef.log)"
# If this script is stopped, stop the jobs too (a partial model is never left: each command writes atomically).
trap 'kill $led_pid $aef_pid 2>/dev/null' INT TERM
status=0
for job in "led:$led_pid" "aef:$aef_pid"; do
  if wait "${job#*:}"; then
    echo "train-models: ${job%%:*} done after $(( $(date +%s) - start )) s"
  else
    code=$?
    echo "train-models: ${job%%:*} FAILED (exit $code); last lines of $OUT/logs/${job%%:*}.log:" >&2
    tail -n 20 "$OUT/logs/${job%%:*}.log" >&2
    status=$code
  fi
done
# The LED's final calibration: market and the assorted scenes, which it never saw.
if [ $status -eq 0 ] && [ "$LED_ASSORTED" = calibrate ] && led_runs; then
  assorted=()
  for d in "$DATA"/assorted_*_w[0-9][0-9]; do [ -f "$d/dataset.json" ] && assorted+=("$d"); done
  if [ ${#assorted[@]} -gt 0 ]; then
    echo "train-models: LED peak rule calibrated again on ${#held[@]} + ${#assorted[@]} held-out datasets ($LED_HELD_SCENE and the assorted scenes)"
    "$BIN" --quiet calibrate-led --weights "$OUT/led/led" --held-out "${held[@]}" "${assorted[@]}" --peak --out "$OUT/led/led" \
      > "$OUT/logs/led_calibration.log" 2>&1 || { status=$?; echo "train-models: LED calibration FAILED (exit $status); see $OUT/logs/led_calibration.log" >&2; }
  fi
  echo "train-models: done after $(( $(date +%s) - start )) s"
fi
exit $status
