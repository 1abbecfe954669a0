#!/usr/bin/env bash
# Builds the restoration training set (docs/restoration.md, `make training-data`): the four training
# scenes park, parking_lot, harbour and market of scenes/training/ (never tanabata, factory or pool)
# rendered clear once at the quick profile, then re-weathered with WEATHERS specs each. The specs are a
# fixed table walked by the index k, so the set is deterministic from its seeds (weather seed = 1000 *
# scene index + k, the indices in SCENE_INDEX). EXTRA_SCENES=1 adds the scenes station and village
# (indices 64 and 65: the weather mixes of 4 and 5 with seeds of their own), measured and not adopted
# for the shipped LED (docs/record/led_variants.md, "Two more training scenes"). Existing outputs are kept
# (the set is a cache: delete OUT to rebuild). Prints its size and time; writes OUT/manifest.json.
# Overcast bases for the lens-drop detector: each scene's `wet` and `snowy` variants (overcast sky,
# wet or snowy ground; the scenes' base lights are all sunny) rendered clear as <scene>_wet and
# <scene>_snowy, then VARIANT_WEATHERS (default 12) rain or snow weathers each, <scene>_wet_wNN and
# <scene>_snowy_wNN. They train the LED only (scripts/train-models.sh), like the photographs.
# Crop variety for the lens-drop detector: PHOTO_WEATHERS (default 4) weathers of each photograph in
# PHOTOS below (Debian's mate-backgrounds nature photos without its RainDrops image, and four of
# scikit-image's sample photos), made clear datasets by `weathergs photo-scene` (synthetic depth),
# as photo_<name>_wNN. They train the LED only (scripts/train-models.sh).
# ASSORTED_SCENES=N (default 16; 0 = none) adds N randomized scenes of the type `assorted` (specs drawn
# by scripts/make-assorted-scenes.py into OUT/scenes/, seed ASSORTED_SEED, default 1), each rendered
# once in one state (index mod 5: 0-1 clear, 2-3 wet, 4 snowy) and re-weathered ASSORTED_WEATHERS
# (default 6) times with the matching effect table (scene index 100 + i: seeds of their own), as
# assorted_NN_wMM, assorted_NN_wet_wMM or assorted_NN_snowy_wMM. Only the LED uses them: by default
# they calibrate its peak rule with market (LED_ASSORTED in scripts/train-models.sh;
# docs/record/led_scenes.md).
# TRAINING_PART=all|base|assorted|validation (default all): make everything, everything but the
# assorted scenes, or only them. `make models` makes the base part first and the assorted scenes
# beside the LED's training (scripts/train-models.sh), which does not need them until its calibration.
# `validation` (into an OUT of its own): only the two validation scenes station and village (scene
# indices 64, 65; rendered clear, WEATHERS weathers each), which no network trains on or is calibrated
# on; they choose between draws of the LED recipe (docs/record/led_scenes.md, "A third draw").
# Not with EXTRA_SCENES=1, which trains on the same scenes.
# RENDER_JOBS (default 2): Blender renders at once (scripts/train-models.sh makes the assorted scenes
# with 1, beside the LED's training).
# LENS_MASK_RULE (default perceptible, the generator's default) sets the lens drops' `mask_rule`, the
# LED's target: `coverage` makes masks/lens/ the drops' blurred lens coverage >= 0.1 instead of where
# they change the view by more than 4 levels (docs/lens_droplets.md); measured, not adopted
# (docs/record/led_targets.md, "Where the drops are, not where they show"). An OUT made with
# the other rule is an error (its cached datasets would mix the two).
#
#   scripts/make-training-data.sh BUILD/apps/weathergs OUT [WEATHERS=12] [PROFILE=quick]
set -euo pipefail
BIN=${1:?usage: make-training-data.sh WEATHERGS_BINARY OUT [WEATHERS] [PROFILE]}
OUT=${2:?usage: make-training-data.sh WEATHERGS_BINARY OUT [WEATHERS] [PROFILE]}
WEATHERS=${3:-12}
PROFILE=${4:-quick}
HERE=$(cd "$(dirname "$0")/.." && pwd)
SCENES=(park parking_lot harbour market)
SCENE_INDEX=(0 1 2 3)  # the weather table's scene index of each
if [ "${EXTRA_SCENES:-0}" = 1 ]; then SCENES+=(station village); SCENE_INDEX+=(64 65); fi
PHOTO_WEATHERS=${PHOTO_WEATHERS:-4}
ASSORTED_SCENES=${ASSORTED_SCENES:-16}
ASSORTED_WEATHERS=${ASSORTED_WEATHERS:-6}
ASSORTED_SEED=${ASSORTED_SEED:-1}
LENS_MASK_RULE=${LENS_MASK_RULE:-perceptible}
TRAINING_PART=${TRAINING_PART:-all}
case $TRAINING_PART in
  all | base | assorted) ;;
  validation)
    if [ "${EXTRA_SCENES:-0}" = 1 ]; then
      echo "make-training-data: TRAINING_PART=validation makes station and village, which EXTRA_SCENES=1 trains on" >&2; exit 2
    fi
    SCENES=(station village) SCENE_INDEX=(64 65) ASSORTED_SCENES=0 ;;
  *) echo "make-training-data: TRAINING_PART must be all, base, assorted or validation, not '$TRAINING_PART'" >&2; exit 2 ;;
esac
# The validation scenes never share an OUT with a training set: train-models.sh trains on every
# <name>_wNN it finds there. A validation OUT's manifest says "part": "validation".
if [ -f "$OUT/manifest.json" ]; then
  holds_validation=$(grep -c '"part": "validation"' "$OUT/manifest.json" || true)
  if [ "$TRAINING_PART" = validation ] && [ "$holds_validation" = 0 ]; then
    echo "make-training-data: $OUT holds a training set; make the validation scenes in an OUT of their own" >&2; exit 2
  fi
  if [ "$TRAINING_PART" != validation ] && [ "$holds_validation" != 0 ]; then
    echo "make-training-data: $OUT holds the validation scenes, which no network may train on; use another OUT" >&2; exit 2
  fi
fi
PART_KEY=$( [ "$TRAINING_PART" = validation ] && echo '"part": "validation", ' || true )
case $LENS_MASK_RULE in
  perceptible) MASK_RULE_KEY="" ;;
  coverage) MASK_RULE_KEY=", \"mask_rule\": \"coverage\"" ;;
  *) echo "make-training-data: LENS_MASK_RULE must be perceptible or coverage, not '$LENS_MASK_RULE'" >&2; exit 2 ;;
esac
if [ -f "$OUT/manifest.json" ]; then  # a set written before the key existed is perceptible
  made_with=$(grep -o '"lens_mask_rule": "[a-z]*"' "$OUT/manifest.json" | cut -d'"' -f4 || true)
  if [ "${made_with:-perceptible}" != "$LENS_MASK_RULE" ]; then
    echo "make-training-data: $OUT/manifest.json: the set was made with lens_mask_rule ${made_with:-perceptible}," \
      "not $LENS_MASK_RULE; use another OUT or delete this one" >&2
    exit 2
  fi
fi
if [ "$ASSORTED_SCENES" -gt 0 ] && [ -f "$OUT/manifest.json" ]; then  # cached renders of other draws would mix in
  drawn_with=$(grep -o '"assorted_seed": [0-9]*' "$OUT/manifest.json" | grep -o '[0-9]*$' || true)
  if [ -n "$drawn_with" ] && [ "$drawn_with" != "$ASSORTED_SEED" ]; then
    echo "make-training-data: $OUT/manifest.json: the assorted scenes were drawn with ASSORTED_SEED $drawn_with," \
      "not $ASSORTED_SEED; use another OUT or delete this one" >&2
    exit 2
  fi
fi
VARIANTS=(wet snowy)
VARIANT_WEATHERS=${VARIANT_WEATHERS:-12}
MATE=/usr/share/backgrounds/mate/nature
SKIMAGE=/usr/lib/python3/dist-packages/skimage/data
PHOTOS=("$MATE/Aqua.jpg" "$MATE/Blinds.jpg" "$MATE/Dune.jpg" "$MATE/FreshFlower.jpg" "$MATE/Garden.jpg"
        "$MATE/GreenMeadow.jpg" "$MATE/LadyBird.jpg" "$MATE/Storm.jpg" "$MATE/TwoWings.jpg" "$MATE/Wood.jpg"
        "$MATE/YellowFlower.jpg" "$SKIMAGE/astronaut.png" "$SKIMAGE/chelsea.png" "$SKIMAGE/coffee.png"
        "$SKIMAGE/motorcycle_left.png")
for p in "${PHOTOS[@]}"; do
  if [ ! -f "$p" ]; then echo "make-training-data: photograph $p not found (run scripts/install-deps.sh)" >&2; exit 2; fi
done
mkdir -p "$OUT/clear" "$OUT/specs"
start=$(date +%s)

# The weather table: effect mix, named intensity, style, wind, lens drops (count, radius, attach, slide).
EFFECTS=(rain snow rain snow none rain+fog snow+fog rain snow rain snow none)
EFFECTS_wet=(rain rain+fog rain none rain rain)      # the wet bases: rain (a clear view among them)
EFFECTS_snowy=(snow snow+fog snow none snow snow)    # the snowy bases: snow
INTENSITIES=(light moderate heavy violent)
STYLES=(paper physical paper)
DROPS=(0 20 40 80 10 60 30 0 50 15 70 25)

spec_for() {  # scene_index k [effect table] -> JSON on stdout
  local si=$1 k=$2
  local -n table=${3:-EFFECTS}
  local effect=${table[$((k % ${#table[@]}))]}
  local intensity=${INTENSITIES[$(((k + si) % 4))]}
  local style=${STYLES[$(((k + 2 * si) % 3))]}
  local drops=${DROPS[$(((k + 3 * si) % ${#DROPS[@]}))]}
  local wind=$(((k * 7 + si * 3) % 5 - 2))
  local slide=0
  if [ $(((k + si) % 5)) -eq 4 ]; then slide=4; fi
  local fx=""
  case $effect in
    rain) fx="\"rain\": {\"intensity\": \"$intensity\", \"wind_m_s\": [$wind, 0, 0]}" ;;
    snow) fx="\"snow\": {\"intensity\": \"$intensity\", \"wind_m_s\": [$wind, 0, 0]}" ;;
    rain+fog) fx="\"rain\": {\"intensity\": \"$intensity\", \"wind_m_s\": [$wind, 0, 0]}, \"fog\": {\"visibility_m\": $((150 + 100 * k))}" ;;
    snow+fog) fx="\"snow\": {\"intensity\": \"$intensity\", \"wind_m_s\": [$wind, 0, 0]}, \"fog\": {\"visibility_m\": $((150 + 100 * k))}" ;;
    none) fx="" ;;
  esac
  if [ "$drops" -gt 0 ]; then
    [ -n "$fx" ] && fx="$fx, "
    fx="$fx\"lens_droplets\": {\"count\": $drops, \"radius_mm\": [0.3, 1.5], \"glass_distance_m\": 0.015, \"slide_speed_mm_s\": $slide$MASK_RULE_KEY}"
  fi
  if [ -z "$fx" ]; then fx="\"fog\": {\"visibility_m\": 5000}"; fi  # a clear view: the faintest haze, no particles, no drops
  echo "{\"seed\": $((1000 * si + k)), \"style\": \"$style\", \"effects\": {$fx}}"
}

weather_all() {  # clear dataset name, scene index in the table, number of weathers [effect table]
  local scene=$1 si=$2 n=$3 table=${4:-EFFECTS} k name
  for k in $(seq 0 $((n - 1))); do
    name=$(printf "%s_w%02d" "$scene" "$k")
    [ -f "$OUT/$name/dataset.json" ] && continue
    spec_for "$si" "$k" "$table" > "$OUT/specs/$name.json"
    echo "== weather $name: $(cat "$OUT/specs/$name.json")"
    "$BIN" --quiet weather --in "$OUT/clear/$scene" --spec "$OUT/specs/$name.json" --out "$OUT/$name" \
      --targets --no-manifest --no-layers
  done
}

render() {  # scene spec, variant (clear, wet, snowy), name of the render under OUT/clear (cached)
  local spec=$1 variant=$2 name=$3
  [ -f "$OUT/clear/$name/dataset.json" ] && return 0
  echo "== render $name ($variant, $PROFILE)"
  "$BIN" --quiet generate --scene "$spec" --weather "$variant" --profile "$PROFILE" --no-colmap --out "$OUT/clear/$name"
}

# Renders "spec|variant|name" items, RENDER_JOBS at a time (default 2: a quick-profile render is
# mostly Blender's single-threaded scene building, so two side by side take about half the wall
# time). Each render is written atomically by `generate`; fails if any of them failed.
RENDER_JOBS=${RENDER_JOBS:-2}
render_all() {
  local pids=() item spec variant name failed=0
  for item in "$@"; do
    IFS='|' read -r spec variant name <<< "$item"
    render "$spec" "$variant" "$name" &
    pids+=($!)
    if [ ${#pids[@]} -ge "$RENDER_JOBS" ]; then
      wait "${pids[0]}" || failed=1
      pids=("${pids[@]:1}")
    fi
  done
  for item in "${pids[@]}"; do wait "$item" || failed=1; done
  if [ $failed -ne 0 ]; then echo "make-training-data: a render failed (see above)" >&2; return 2; fi
}

make_scenes() {  # the training scenes (SCENES) and their overcast bases (unless `clear_only`)
  local renders=() si vi
  for si in "${!SCENES[@]}"; do
    renders+=("$HERE/scenes/training/${SCENES[$si]}.json|clear|${SCENES[$si]}")
    [ "${1:-}" = clear_only ] && continue
    for vi in "${!VARIANTS[@]}"; do
      renders+=("$HERE/scenes/training/${SCENES[$si]}.json|${VARIANTS[$vi]}|${SCENES[$si]}_${VARIANTS[$vi]}")
    done
  done
  render_all "${renders[@]}"
  for si in "${!SCENES[@]}"; do
    weather_all "${SCENES[$si]}" "${SCENE_INDEX[$si]}" "$WEATHERS"
  done
  [ "${1:-}" = clear_only ] && return 0

  # The overcast bases (scene index 20 + 2 * scene + variant in the weather table: seeds of their own).
  for si in "${!SCENES[@]}"; do
    for vi in "${!VARIANTS[@]}"; do
      variant=${VARIANTS[$vi]}
      weather_all "${SCENES[$si]}_$variant" "$((20 + 2 * ${SCENE_INDEX[$si]} + vi))" "$VARIANT_WEATHERS" "EFFECTS_$variant"
    done
  done
}

make_photos() {
  # Photographs: a 16-view pan at the profile's size, then PHOTO_WEATHERS weathers (scene index 4 + i
  # in the weather table, so their mixes differ from the scenes').
  size=$( [ "$PROFILE" = quick ] && echo "--width 300 --height 200" || echo "--width 600 --height 400" )
  for pi in "${!PHOTOS[@]}"; do
    photo=${PHOTOS[$pi]}
    stem=$(basename "${photo%.*}" | tr 'A-Z' 'a-z')
    scene="photo_$stem"
    if [ ! -f "$OUT/clear/$scene/dataset.json" ]; then
      "$BIN" --quiet photo-scene --photo "$photo" $size --out "$OUT/clear/$scene" > /dev/null
    fi
    weather_all "$scene" "$((4 + pi))" "$PHOTO_WEATHERS"
  done
}

# Assorted scenes: randomized layouts, materials and skies, one state each.
make_assorted() {
  local renders=() names=() tables=() i scene variant name table
  /usr/bin/python3 "$HERE/scripts/make-assorted-scenes.py" "$ASSORTED_SCENES" "$OUT/scenes" "$ASSORTED_SEED" > /dev/null
  for i in $(seq 0 $((ASSORTED_SCENES - 1))); do
    scene=$(printf "assorted_%02d" "$i")
    case $((i % 5)) in
      0 | 1) variant=clear name=$scene table=EFFECTS ;;
      2 | 3) variant=wet name=${scene}_wet table=EFFECTS_wet ;;
      *) variant=snowy name=${scene}_snowy table=EFFECTS_snowy ;;
    esac
    renders+=("$OUT/scenes/$scene.json|$variant|$name") names+=("$name") tables+=("$table")
  done
  render_all "${renders[@]}"
  for i in "${!names[@]}"; do
    weather_all "${names[$i]}" "$((100 + i))" "$ASSORTED_WEATHERS" "${tables[$i]}"
  done
}

case $TRAINING_PART in
  all | base) make_scenes ;;
  validation) make_scenes clear_only ;;
esac
case $TRAINING_PART in all | base) make_photos ;; esac
case $TRAINING_PART in all | assorted) if [ "$ASSORTED_SCENES" -gt 0 ]; then make_assorted; fi ;; esac

seconds=$(( $(date +%s) - start ))
datasets=$(find "$OUT" -mindepth 2 -maxdepth 2 -name dataset.json -not -path "$OUT/clear/*" | wc -l)
views=$(find "$OUT" -path "$OUT/clear" -prune -o -path "*/images/*.png" -print | wc -l)
size=$(du -sm "$OUT" | cut -f1)
photos_made=$(find "$OUT/clear" -mindepth 2 -maxdepth 2 -name dataset.json -path "$OUT/clear/photo_*" | wc -l)
assorted_made=$(find "$OUT/clear" -mindepth 2 -maxdepth 2 -name dataset.json -path "$OUT/clear/assorted_*" | wc -l)
cat > "$OUT/manifest.json" <<EOF
{"format": "weathergs-training-set", $PART_KEY"scenes": [$(printf '"%s", ' "${SCENES[@]}" | sed 's/, $//')], "profile": "$PROFILE", "lens_mask_rule": "$LENS_MASK_RULE",
 "weathers_per_scene": $WEATHERS, "overcast_variants": [$(printf '"%s", ' "${VARIANTS[@]}" | sed 's/, $//')], "weathers_per_variant": $VARIANT_WEATHERS,
 "photos": $photos_made, "weathers_per_photo": $PHOTO_WEATHERS, "assorted_scenes": $assorted_made, "weathers_per_assorted": $ASSORTED_WEATHERS, "assorted_seed": $ASSORTED_SEED, "datasets": $datasets, "views": $views, "size_mb": $size,
 "seconds_this_run": $seconds, "recipe": "scripts/make-training-data.sh"}
EOF
echo "training set: $datasets datasets, $views views, $size MB in $OUT ($seconds s this run)"
