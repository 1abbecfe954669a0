#!/usr/bin/env bash
# The training runs behind docs/record/readings.md: the four readings of the paper that the benchmark
# does not reproduce, each tested on the tuning scenes (make_tuning_scenes.sh: village and station,
# never the benchmark's) at the default schedule, one thread per run, seed 0.
# A CELL is <scene>_<weather>:<kind>:
#   3dgs, weathergs, weathergs-no-led, gs-w-lite, nerf, derainnerf   reconstruct --method KIND
#   gs-w-lite-novis   gs-w-lite with its visibility map pinned open (visibility_weight 1000): the
#                     per-view appearance alone, to tell which half of it carries its gain
#   no-particles      3DGS on the generator's no_particles target (every particle gone, lens drops
#                     kept; image_level.py makes it): what a particle filter that loses no detail gives
#   rain-<intensity>  3dgs and weathergs on the scene's rain made again at that intensity (light or
#                     moderate; the tuning scenes' own is heavy), lens drops as before: the gain
#                     against how much the rain costs 3DGS
# Usage: training.sh WEATHERGS_BINARY TUNING_DIR READINGS_DIR CELL...   (TUNING_DIR: make_tuning_scenes.sh's
# output; READINGS_DIR: image_level.py's; runs go to READINGS_DIR/runs/<scene>_<weather>/<kind>/, and
# a finished run is kept, a stopped one resumes from its checkpoint)
set -euo pipefail
W=$(realpath "${1:?usage: training.sh WEATHERGS_BINARY TUNING_DIR READINGS_DIR CELL...}")
TUNING=$(realpath "${2:?usage}"); OUT=$(realpath -m "${3:?usage}"); shift 3
fail() { echo "training.sh: $*" >&2; exit 2; }
reconstruct() {  # DATA METHOD RUN [more flags]
  local data=$1 method=$2 run=$3; shift 3
  [ -f "$run/results.json" ] && return 0
  mkdir -p "$(dirname "$run")"
  "$W" --quiet --threads 1 reconstruct --data "$data" --method "$method" --seed 0 --out "$run" "$@" > "$run.log" 2>&1 ||
    fail "reconstruct $method on $data failed: $run.log"
}
for cell in "$@"; do
  IFS=: read -r name kind <<<"$cell"
  data="$TUNING/$name"
  [ -f "$data/dataset.json" ] || fail "$data: missing (make_tuning_scenes.sh makes it)"
  run="$OUT/runs/$name/$kind"
  echo "== $(date -Is) $name $kind"
  case $kind in
    3dgs|weathergs|weathergs-no-led|gs-w-lite|nerf|derainnerf) reconstruct "$data" "$kind" "$run" ;;
    gs-w-lite-novis)
      mkdir -p "$OUT/runs"; echo '{"visibility_weight": 1000}' > "$OUT/runs/novis.json"
      reconstruct "$data" gs-w-lite "$run" --train-options "$OUT/runs/novis.json" ;;
    no-particles)
      target="$OUT/$name/data/targets/no_particles"
      [ -d "$target" ] || fail "$target: missing (image_level.py $name makes it)"
      if [ ! -f "$run/results.json" ]; then
        mkdir -p "$run"
        resume=(); [ -f "$run/model/checkpoint.bin" ] && resume=(--resume)
        "$W" --quiet --threads 1 train --data "$data" --images-dir "$target" --seed 0 --out "$run/model" "${resume[@]}" > "$run.log" 2>&1 &&
          "$W" --quiet render --model "$run/model" --data "$data" --split test --method no-particles --out "$run/renders" >> "$run.log" 2>&1 &&
          "$W" --quiet evaluate --gt "$data" --renders "$run/renders" --method no-particles -o "$run/results.json" >> "$run.log" 2>&1 ||
          fail "no-particles on $name failed: $run.log"
      fi ;;
    rain-light|rain-moderate)
      [[ $name == *_rain ]] || fail "$cell: the rain intensities are made from a rain dataset"
      intensity=${kind#rain-}; scene=${name%_rain}
      rdata="$OUT/data/${scene}_rain_$intensity"
      if [ ! -f "$rdata/sparse/0/points3D.txt" ] && [ ! -f "$rdata/sparse/0/points3D.bin" ]; then
        rm -rf "$rdata"; mkdir -p "$OUT/data"
        /usr/bin/python3 -c 'import json, sys; s = json.load(open(sys.argv[1])); s["effects"]["rain"]["intensity"] = sys.argv[2]; json.dump(s, open(sys.argv[3], "w"))' \
          "$TUNING/rain.json" "$intensity" "$OUT/data/rain_$intensity.json"
        "$W" --quiet weather --in "$TUNING/clear_${scene}_wet" --spec "$OUT/data/rain_$intensity.json" --out "$rdata"
        "$W" --quiet --threads 1 triangulate --data "$rdata" --images images --views all
        "$W" --quiet --threads 1 triangulate --data "$rdata" --images clean --views all
      fi
      for m in 3dgs weathergs; do reconstruct "$rdata" "$m" "$run/$m"; done ;;
    *) fail "$cell: unknown kind '$kind'" ;;
  esac
done
echo "== $(date -Is) done"
