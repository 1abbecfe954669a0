#!/usr/bin/env bash
# The learned AEF against the classical top-hat on a generated suite (docs/restoration.md): PSNR/SSIM of
# the train views against the no-particle target (particles removed, lens drops kept), for the input,
# the top-hat on every view, the learned plugin of the variant's weather (forced), and the default
# (`--method learned --task auto`: the selector picks derain, desnow or none per scene); what each does
# to clear views (the clean images, against themselves); and the selector's choices on the weathered and
# the clean images, per scene and per view.
# Usage: benchmarks/experiments/restoration/restoration_aef.sh WEATHERGS SUITE_DIR [OUT] [WEIGHTS_DIR]
#   EVAL=BINARY: the weathergs that runs `evaluate` (a build with the evaluator part; default WEATHERGS).
set -euo pipefail
W=${1:?usage: restoration_aef.sh WEATHERGS SUITE_DIR [OUT] [WEIGHTS]}
SUITE=${2:?usage: restoration_aef.sh WEATHERGS SUITE_DIR [OUT] [WEIGHTS]}
OUT=${3:-$(mktemp -d)}
WEIGHTS=${4:-}
EVAL=${EVAL:-$W}
wflag=()
[ -n "$WEIGHTS" ] && wflag=(--weights "$WEIGHTS")
mkdir -p "$OUT"
psnr() {  # "inf" where the images are identical (evaluate writes null)
  /usr/bin/python3 -c 'import json,sys; p=json.load(open(sys.argv[1]))["metrics"]["psnr"]; print("inf" if p is None else "%.2f" % p)' "$1"
}
# choice FILTER_JSON EXPECTED: the scene's plugin and "right/total" of the per-view plugins (a --select per-view run).
choice() {
  /usr/bin/python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); v=j["views"]
print(j["selection"]["scene_plugin"], "%d/%d" % (sum(x["plugin"] == sys.argv[2] for x in v), len(v)))' "$1" "$2"
}
ms() { /usr/bin/python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); print("%.0f" % (1000*j["seconds_per_view"]))' "$1"; }
split_dir() {  # a folder of symlinks to the train views of SRC (evaluate scores exactly one split)
  local src=$1 data=$2 dst=$3
  rm -rf "$dst"; mkdir -p "$dst"
  for v in $(/usr/bin/python3 -c 'import json,sys; print(" ".join(json.load(open(sys.argv[1]))["splits"]["train"]))' "$data/dataset.json"); do
    ln -s "$(readlink -f "$src/$v.png")" "$dst/$v.png"
  done
}
score() {  # score NAME DATASET DIR GT -> PSNR
  split_dir "$3" "$2" "$OUT/$1/s_$(basename "$3")"
  "$EVAL" --quiet evaluate --gt "$2" --renders "$OUT/$1/s_$(basename "$3")" --method x --split train $4 --no-lpips \
    -o "$OUT/$1/$(basename "$3").json" > /dev/null
  psnr "$OUT/$1/$(basename "$3").json"
}
echo "| variant | input | top-hat | learned (forced) | default (auto) | clear: top-hat | clear: learned (forced) | clear: default | selector on weathered: scene, views right | on clean: scene, views right | ms/view learned |"
echo "|---|---:|---:|---:|---:|---:|---:|---:|---|---|---:|"
for d in "$SUITE"/*/; do
  d=${d%/}; name=$(basename "$d")
  [ -f "$d/dataset.json" ] && [ -d "$d/targets/no_particles" ] || continue
  case $name in *rain*) plugin=derain ;; *snow*) plugin=desnow ;; *) continue ;; esac
  mkdir -p "$OUT/$name"
  "$W" --quiet filter --data "$d" --method tophat --task always --out "$OUT/$name/tophat" > /dev/null
  "$W" --quiet filter --data "$d" --method learned --task $plugin "${wflag[@]}" --out "$OUT/$name/forced" > /dev/null
  "$W" --quiet filter --data "$d" --method learned --task auto --select per-view "${wflag[@]}" --out "$OUT/$name/perview" > /dev/null
  "$W" --quiet filter --data "$d" --method learned --task auto "${wflag[@]}" --out "$OUT/$name/auto" > /dev/null
  "$W" --quiet filter --data "$d" --images clean --method tophat --task always --out "$OUT/$name/clear_tophat" > /dev/null
  "$W" --quiet filter --data "$d" --images clean --method learned --task $plugin "${wflag[@]}" --out "$OUT/$name/clear_forced" > /dev/null
  "$W" --quiet filter --data "$d" --images clean --method learned --task auto "${wflag[@]}" --out "$OUT/$name/clear_auto" > /dev/null
  "$W" --quiet filter --data "$d" --images clean --method learned --task auto --select per-view "${wflag[@]}" \
    --out "$OUT/$name/clear_perview" > /dev/null
  nt="--ground-truth no_particles"
  pi=$(score "$name" "$d" "$d/images" "$nt")
  pt=$(score "$name" "$d" "$OUT/$name/tophat" "$nt")
  pf=$(score "$name" "$d" "$OUT/$name/forced" "$nt")
  pa=$(score "$name" "$d" "$OUT/$name/auto" "$nt")
  ct=$(score "$name" "$d" "$OUT/$name/clear_tophat" "")
  cf=$(score "$name" "$d" "$OUT/$name/clear_forced" "")
  ca=$(score "$name" "$d" "$OUT/$name/clear_auto" "")
  read -r sw vw <<< "$(choice "$OUT/$name/perview/filter.json" $plugin)"
  read -r sc vc <<< "$(choice "$OUT/$name/clear_perview/filter.json" none)"
  echo "| $name | $pi | $pt | $pf | $pa | $ct | $cf | $ca | $sw, $vw | $sc, $vc | $(ms "$OUT/$name/forced/filter.json") |"
done
