#!/usr/bin/env bash
# The classical particle filter (weathergs filter) on a generated suite: PSNR/SSIM of the train views
# against the no-particle target (particles removed, lens drops kept), before and after filtering, and
# what the filter does to clear views (the clean images filtered, against themselves).
# Usage: benchmarks/experiments/restoration/restoration_filter.sh WEATHERGS SUITE_DIR [OUT]   (datasets need generate --targets)
set -euo pipefail
W=${1:?usage: restoration_filter.sh WEATHERGS SUITE_DIR [OUT]}
SUITE=${2:?usage: restoration_filter.sh WEATHERGS SUITE_DIR [OUT]}
OUT=${3:-$(mktemp -d)}
mkdir -p "$OUT"
metric() { /usr/bin/python3 -c 'import json,sys; m=json.load(open(sys.argv[1]))["metrics"]; print("%.2f %.4f" % (m["psnr"], m["ssim"]))' "$1"; }
# A folder of symlinks to the split's views of DIR (evaluate scores exactly one split).
split_dir() {
  local src=$1 data=$2 split=$3 dst=$4
  rm -rf "$dst"; mkdir -p "$dst"
  for v in $(/usr/bin/python3 -c 'import json,sys; print(" ".join(json.load(open(sys.argv[1]))["splits"][sys.argv[2]]))' "$data/dataset.json" "$split"); do
    ln -s "$(readlink -f "$src/$v.png")" "$dst/$v.png"
  done
}
echo "| variant | input vs target (PSNR / SSIM) | filtered vs target | gain dB | masked % | clear view filtered vs itself | ms/view |"
echo "|---|---|---|---:|---:|---|---:|"
for d in "$SUITE"/*/; do
  d=${d%/}; name=$(basename "$d")
  [ -f "$d/dataset.json" ] && [ -d "$d/targets/no_particles" ] || continue
  mkdir -p "$OUT/$name"
  "$W" --quiet filter --method tophat --task always --data "$d" --out "$OUT/$name/filtered" > /dev/null
  "$W" --quiet filter --method tophat --task always --data "$d" --images clean --out "$OUT/$name/filtered_clean" > /dev/null
  split_dir "$d/images" "$d" train "$OUT/$name/in"
  split_dir "$OUT/$name/filtered" "$d" train "$OUT/$name/out"
  split_dir "$OUT/$name/filtered_clean" "$d" train "$OUT/$name/out_clean"
  for k in in out; do
    "$W" --quiet evaluate --gt "$d" --renders "$OUT/$name/$k" --method "$k" --split train --ground-truth no_particles \
      --no-lpips -o "$OUT/$name/$k.json" > /dev/null
  done
  "$W" --quiet evaluate --gt "$d" --renders "$OUT/$name/out_clean" --method clear --split train --no-lpips \
    -o "$OUT/$name/clear.json" > /dev/null
  read -r pi si <<< "$(metric "$OUT/$name/in.json")"
  read -r po so <<< "$(metric "$OUT/$name/out.json")"
  read -r pc sc <<< "$(metric "$OUT/$name/clear.json")"
  stats=$(/usr/bin/python3 -c 'import json,sys; j=json.load(open(sys.argv[1])); v=j["views"]; print("%.1f %.1f" % (100*sum(x["mask_fraction"] for x in v)/len(v), 1000*j["seconds"]/len(v)))' "$OUT/$name/filtered/filter.json")
  read -r masked ms <<< "$stats"
  gain=$(/usr/bin/python3 -c "print('%+.2f' % ($po - $pi))")
  echo "| $name | $pi / $si | $po / $so | $gain | $masked | $pc / $sc | $ms |"
done
