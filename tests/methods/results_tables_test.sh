#!/usr/bin/env bash
# `make results` (scripts/results-tables.sh) on a small results archive: the section
# between the markers is rewritten with the archive's state, the paper's tables, the curves and the
# carry-over to a second suite (CARRY_TO), the
# rest of the page is kept byte for byte, a second run gives the same page, and bad input (no matrix,
# markers missing, a broken result) is refused with exit 2 before the page is touched.
# Usage: results_tables_test.sh WEATHERGS_BINARY WORK_DIR SOURCE_DIR ARCHIVE_SUITE_DIR (runs of 3dgs and oracle
# on pool_rain, seed 1, with curves: the workflow test makes them)
set -euo pipefail
W=$1; T=$2; SRC=$3; ARCHIVE=$4
rm -rf "$T"; mkdir -p "$T"
fail() { echo "FAIL: $*" >&2; exit 1; }
# A copy of a real archive suite folder (the workflow test's tiny runs: method_info.recipe is needed),
# with a matrix that also lists a seed not yet run.
A="$T/results/tiny"
mkdir -p "$T/results"; cp -r "$ARCHIVE" "$A"
cat > "$A/matrix.json" <<'JSON'
{"format": "weathergs-archive-matrix", "version": 1, "suite": "tiny", "variants": ["pool_rain"],
 "groups": [{"methods": ["3dgs", "oracle"], "seeds": [1, 2]}]}
JSON
DOC="$T/results.md"
printf '# Results\n\nBefore.\n\n<!-- results-tables: begin -->\nold text\n<!-- results-tables: end -->\n\nAfter.\n' > "$DOC"
out=$(bash "$SRC/scripts/results-tables.sh" "$W" "$A" "$DOC" "$T/images")
grep -q "from 2 runs" <<<"$out" || fail "summary: $out"
grep -q "^# Results$" "$DOC" && grep -q "^Before.$" "$DOC" && grep -q "^After.$" "$DOC" || fail "the page around the section changed"
grep -q "old text" "$DOC" && fail "the old section is still there"
grep -q "^2 archived runs.$" "$DOC" || fail "no run count"
grep -q "^done 2, stale 0, missing 2 of 4$" "$DOC" || { cat "$DOC"; fail "no archive state line"; }
grep -q "at its commit none (not in a git work tree)" "$DOC" || fail "no commit line"
grep -q "^### Table I" "$DOC" || fail "no Table I (one level under the page's title)"
grep -q "^# WeatherGS benchmark" "$DOC" && fail "the tables' own title is kept"
grep -q "| oracle (reference) |" "$DOC" || fail "no oracle row"
for v in pool_rain; do
  [ -s "$T/images/$v.png" ] || fail "no curve image for $v"
  grep -qF -e "- $v: ![$v](images/$v.png)" "$DOC" || fail "no link to the curve of $v"
done
grep -q "^### Does the verdict carry over? The suite .paper.$" "$DOC" && grep -q "^No run archived in .*/results/paper. yet.$" "$DOC" ||
  fail "no carry-over section saying that the sibling suite 'paper' holds no run"
cp "$DOC" "$T/first.md"
# A target suite with runs (CARRY_TO): the carry-over table (weathergs carry-over) under its heading.
mkdir -p "$T/target"; cp -r "$A/pool_rain" "$T/target/"; cp "$DOC" "$T/carry.md"
CARRY_TO="$T/target" bash "$SRC/scripts/results-tables.sh" "$W" "$A" "$T/carry.md" "$T/images" > /dev/null
grep -q "^### Does the verdict carry over? The suite .target.$" "$T/carry.md" || fail "no carry-over heading for CARRY_TO"
grep -q "^| oracle - 3dgs | PSNR | 1 | .* | 1.00 | 1 of 1 | 0.500 | same sign on 1 of 1, too few variants" "$T/carry.md" ||
  { cat "$T/carry.md"; fail "no carry-over row for the oracle's gap"; }
bash "$SRC/scripts/results-tables.sh" "$W" "$A" "$DOC" "$T/images" > /dev/null
cmp -s "$DOC" "$T/first.md" || fail "a second run changed the page"

# Refused before the page is touched (exit 2, naming the problem).
expect_refused() {  # what-to-find, then the script's arguments
  local want=$1; shift
  set +e; msg=$(bash "$SRC/scripts/results-tables.sh" "$@" 2>&1); rc=$?; set -e
  [ $rc = 2 ] || fail "exit $rc, expected 2 ($want): $msg"
  grep -qF "$want" <<<"$msg" || fail "expected '$want' in: $msg"
  cmp -s "$DOC" "$T/first.md" || fail "the page changed although refused ($want)"
}
mkdir -p "$T/empty"
expect_refused "matrix.json: missing" "$W" "$T/empty" "$DOC" "$T/images"
printf '# no markers\n' > "$T/plain.md"
expect_refused "results-tables: begin" "$W" "$A" "$T/plain.md" "$T/images"
echo '{"not": "a result"}' > "$A/pool_rain/3dgs/seed1/results.json"
set +e; msg=$(bash "$SRC/scripts/results-tables.sh" "$W" "$A" "$DOC" "$T/images" 2>&1); rc=$?; set -e
[ $rc = 2 ] || fail "a broken result: exit $rc, expected 2: $msg"
grep -q "pool_rain/3dgs/seed1/results.json" <<<"$msg" || fail "the broken result is not named: $msg"
cmp -s "$DOC" "$T/first.md" || fail "the page changed although a result is broken"
echo "results_tables: ok"
