#!/usr/bin/env bash
# Real clients read what weathergs writes (docs/interop.md). Usage:
#   interop/run.sh BUILD [OUT]      (make interop: installs the npm packages and Debian chromium first)
# 1. a small dataset: pool (tiny profile, clear weather) from Blender when it is installed, else
#    `weathergs example`; a short 3DGS training on it and `weathergs render` of its test views;
# 2. @playcanvas/splat-transform converts point_cloud.ply to PLY and CSV, read back and compared;
# 3. @mkkellogg/gaussian-splats-3d (Three.js) in headless Chromium renders the model from each test
#    camera, compared with weathergs' render (PSNR >= 25 dB);
# 4. the HTML leaderboard of the example benchmark in headless Chromium: screenshot, DOM numbers ==
#    results files;
# 5. the results browser (`weathergs report`) of a small `make demo` in headless Chromium.
# Prints one JSON report per check and writes OUT/report.json (default BUILD/interop). Exit 0 only
# when every check passed.
set -euo pipefail
BUILD=$(readlink -f "${1:?usage: interop/run.sh BUILD [OUT]}")
HERE=$(cd "$(dirname "$0")" && pwd)
OUT=$(readlink -m "${2:-$BUILD/interop}")
W="$BUILD/apps/weathergs"
[ -x "$W" ] || { echo "interop: $W not built" >&2; exit 2; }
[ -d "$HERE/node_modules/@playcanvas/splat-transform" ] || { echo "interop: run 'make interop' (npm packages missing)" >&2; exit 2; }
ITER=${INTEROP_ITERATIONS:-500}
rm -rf "$OUT"; mkdir -p "$OUT"
cd "$HERE"

# 1. Dataset, model, renders.
if command -v blender >/dev/null; then
  "$W" --quiet generate --scene "$HERE/../scenes/pool.json" --weather clear --profile tiny --no-colmap \
    --cache "$BUILD/interop-cache" --out "$OUT/data"
  DATA_KIND="pool, tiny profile (192x128, Blender), clear"
else
  "$W" --quiet example -o "$OUT/example" --width 240 --height 160 --views 17
  ln -s example/datasets/park_rain "$OUT/data"
  DATA_KIND="weathergs example park_rain (240x160, no Blender here)"
fi
"$W" --quiet train --data "$OUT/data" --images clean --iterations "$ITER" --random-init-count 20000 --seed 1 --out "$OUT/run"
mkdir -p "$OUT/renders"
"$W" --quiet render --model "$OUT/run" --split test --out "$OUT/renders/test"
"$W" --quiet render --model "$OUT/run" --split train --out "$OUT/renders/train"

status=0
# 2. splat-transform.
node splat_transform_check.mjs "$OUT/run/point_cloud.ply" "$OUT/splat_transform" > "$OUT/splat_transform.json" || status=1
cat "$OUT/splat_transform.json"; echo

# 3. Three.js viewer: every test view must agree (>= 25 dB); the train views are rendered and reported
#    too, without a bar (docs/interop.md: why they score lower).
for split in test train; do
  bar=25; [ $split = train ] && bar=0
  views=$(node -e 'const d=require(process.argv[1]);console.log(d.splits[process.argv[2]].join(" "))' "$OUT/data/dataset.json" $split)
  for v in $views; do
    node viewer_check.mjs --weathergs "$W" --ply "$OUT/run/point_cloud.ply" --cameras "$OUT/data/cameras.json" \
      --view "$v" --ours "$OUT/renders/$split/$v.png" --out "$OUT/viewer" --min-psnr $bar > "$OUT/viewer_$v.json" || status=1
    cat "$OUT/viewer_$v.json"; echo
  done
done

# 4. HTML leaderboard of the example benchmark (three toy methods on four datasets).
"$W" --quiet example -o "$OUT/bench"
results=(); mkdir -p "$OUT/results"
for r in "$OUT"/bench/renders/*/*; do
  m=$(basename "$(dirname "$r")"); d=$(basename "$r")
  "$W" --quiet evaluate --gt "$OUT/bench/datasets/$d" --renders "$r" --method "$m" -o "$OUT/results/${m}_$d.json"
  results+=("$OUT/results/${m}_$d.json")
done
"$W" --quiet leaderboard "${results[@]}" --format html -o "$OUT/leaderboard.html"
node leaderboard_check.mjs "$OUT/leaderboard.html" "$OUT/leaderboard" "${results[@]}" > "$OUT/leaderboard.json" || status=1
cat "$OUT/leaderboard.json"; echo

# 5. The results browser made from the demo's output (`make demo` small: scripts/demo.sh, which ends
#    with `weathergs report`): images, links, numbers against the results files, sorting, the zoom;
#    a full-page screenshot (docs/images/report.png is one).
if command -v blender >/dev/null && command -v colmap >/dev/null; then
  DEMO_ITERATIONS=${INTEROP_DEMO_ITERATIONS:-300} WEATHERGS_CACHE="$BUILD/interop-cache" \
    bash "$HERE/../scripts/demo.sh" "$W" "$OUT/demo" > "$OUT/demo.log" 2>&1 || { echo "interop: the demo failed"; tail -30 "$OUT/demo.log"; status=1; }
  node report_check.mjs "$OUT/demo/report" "$OUT/demo" "$OUT/report.png" > "$OUT/report_page.json" || status=1
else
  echo '{"ok": false, "problems": ["blender and colmap are needed to make the demo the results browser is checked on"]}' > "$OUT/report_page.json"
  status=1
fi
cat "$OUT/report_page.json"; echo

node -e '
const fs = require("fs"); const [out, kind, iter, st] = process.argv.slice(1);
const read = (f) => JSON.parse(fs.readFileSync(f, "utf8"));
const viewers = fs.readdirSync(out).filter((f) => /^viewer_.*\.json$/.test(f)).map((f) => read(`${out}/${f}`));
const report = { dataset: kind, iterations: Number(iter), node: process.version,
  splat_transform: read(`${out}/splat_transform.json`), viewer: viewers.map(({ console: _, ...v }) => v),
  leaderboard: read(`${out}/leaderboard.json`), report_page: read(`${out}/report_page.json`), ok: st === "0" };
fs.writeFileSync(`${out}/report.json`, JSON.stringify(report, null, 2));
console.log(`interop: ${report.ok ? "all checks passed" : "FAILED"} (${out}/report.json); viewer PSNR: ` +
  viewers.map((v) => `${v.view} ${v.compare.psnr.toFixed(2)} dB${v.min_psnr > 0 ? " (test view)" : ""}`).join(", "));
' "$OUT" "$DATA_KIND" "$ITER" "$status"
exit $status
