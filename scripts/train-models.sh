#!/usr/bin/env bash
# Retrains every weight file this project ships (models/README.md) from the training set of
# scripts/make-training-data.sh: `make models`. The last weather of each training scene (*_w11 with the
# default 12) is held out for the calibration and the reported metrics; everything else trains.
#
#   scripts/train-models.sh BUILD/apps/weathergs TRAINING_DATA OUT_MODELS_DIR [ITERATIONS]
set -euo pipefail
BIN=${1:?usage: train-models.sh WEATHERGS_BINARY TRAINING_DATA OUT [ITERATIONS]}
DATA=${2:?usage: train-models.sh WEATHERGS_BINARY TRAINING_DATA OUT [ITERATIONS]}
OUT=${3:?usage: train-models.sh WEATHERGS_BINARY TRAINING_DATA OUT [ITERATIONS]}
ITERATIONS=${4:-3000}
train=() held=()
for d in "$DATA"/*_w[0-9][0-9]; do
  [ -f "$d/dataset.json" ] || continue
  last=$(ls -d "${d%_w*}"_w[0-9][0-9] | sort | tail -1)
  if [ "$d" = "$last" ]; then held+=("$d"); else train+=("$d"); fi
done
if [ ${#train[@]} -eq 0 ]; then echo "train-models: no training datasets in $DATA (run make training-data)" >&2; exit 2; fi
mkdir -p "$OUT/led"
echo "train-models: LED on ${#train[@]} datasets, calibrated on ${#held[@]} held out"
"$BIN" --threads 1 train-led --data "${train[@]}" --held-out "${held[@]}" --out "$OUT/led/led" \
  --iterations "$ITERATIONS" --seed 1 --threads 1
