#!/usr/bin/env bash
# `make demo` checks what it needs before any work: with the LPIPS model made unavailable, or a
# Blender that is not there, scripts/demo.sh stops within seconds, before Blender starts, and leaves
# no output folder behind.
set -u
wgs="$1"; work="$2"; src="$3"
rm -rf "$work"; mkdir -p "$work"
fail=0
check() {
  local name="$1" expect="$2"; shift 2
  local out="$work/$name/demo_out" log="$work/$name.log"
  mkdir -p "$work/$name"
  local t0=$SECONDS
  env "$@" bash "$src/scripts/demo.sh" "$wgs" "$out" > "$log" 2>&1
  local rc=$? dt=$((SECONDS - t0))
  if [ $rc = 0 ]; then echo "$name: demo.sh exited 0"; fail=1; fi
  if [ -e "$out" ]; then echo "$name: $out was left behind"; fail=1; fi
  if [ $dt -gt 30 ]; then echo "$name: took $dt s, the check must come before any work"; fail=1; fi
  if grep -q "rule generate\|Blender 3\|snakemake" "$log"; then echo "$name: work started"; fail=1; fi
  if ! grep -q "$expect" "$log"; then echo "$name: the message does not name '$expect'"; fail=1; fi
  [ $fail = 0 ] || { echo "--- $log"; cat "$log"; }
}
check no_lpips "LPIPS" WEATHERGS_LPIPS_MODEL="$work/none.onnx"
# A PATH without Blender (and everything else the script needs kept).
mkdir -p "$work/bin"
for t in bash env dirname realpath cat date mkdir rm snakemake colmap; do
  p=$(command -v "$t") && ln -sf "$p" "$work/bin/$t"
done
check no_blender "Blender" PATH="$work/bin"
[ $fail = 0 ] && echo "demo.sh stops before any work when LPIPS or Blender is missing"
exit $fail
