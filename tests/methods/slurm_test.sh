#!/usr/bin/env bash
# methods/slurm (slow; `make test-slurm`): the suite through the Slurm profile on a real one-node Slurm
# started here (scripts/slurm-local.sh; munged, slurmctld and slurmd are this test's processes and are
# stopped when it ends, whatever happens). Tiny pool_rain, 3dgs + oracle, one seed:
#   1. one training job is scancel'led mid-run: snakemake names the cancelled cell and goes on with
#      the others (keep-going); 2. the next invocation reruns only that cell and completes;
#   3. every job Slurm ran is in its job-completion log: COMPLETED, except the cancelled one;
#   4. a local run of the same seeds on the same generated data gives the same leaderboard, and the
#      same model bytes for the cell that was cancelled and rerun;
#   5. a job whose memory request is too small fails with a message naming the rule and the request;
#   6. two generate jobs running at once on one clean-render cache: one renders, the other waits for
#      it and reuses the entry (the cache's file lock).
# Usage: slurm_test.sh WEATHERGS_BINARY WORK_DIR   (WORK_DIR is removed first). Exit 77: skipped.
set -euo pipefail
SRC=$(cd "$(dirname "$0")/../.." && pwd)
WGS=$(realpath "$1")
WORK=$(realpath -m "$2")
for tool in snakemake blender colmap munged slurmctld slurmd sbatch; do
  command -v "$tool" > /dev/null || { echo "methods/slurm: $tool is not installed (scripts/install-deps.sh slurm): skipped"; exit 77; }
done
[ "$(id -u)" = 0 ] || { echo "methods/slurm: needs root to run slurmd: skipped"; exit 77; }

CLUSTER=$WORK/cluster
# Daemons left by an earlier run that was killed (SIGKILL skips traps) go before their pid files do.
[ -d "$CLUSTER" ] && bash "$SRC/scripts/slurm-local.sh" stop "$CLUSTER"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
trap 'bash "$SRC/scripts/slurm-local.sh" stop "$CLUSTER"' EXIT
trap 'exit 1' INT TERM HUP  # through the EXIT trap
eval "$(bash "$SRC/scripts/slurm-local.sh" start "$CLUSTER" 2 8000)"
export USER=${USER:-weathergs}

fail() { echo "methods/slurm: FAILED: $*" >&2; exit 1; }
CFG=(weathergs="$WGS" scenes="$SRC/scenes" cache="$WORK/cache" profile=tiny 'variants=[pool_rain]'
     'methods=[3dgs,oracle]' 'seeds=[1]' iterations=300 threads=1)
on_slurm() { snakemake -s "$SRC/workflow/Snakefile" --profile "$SRC/workflow/profiles/slurm" --config out="$WORK/slurm_out" "${CFG[@]}" "$@"; }
CELL=$WORK/slurm_out/runs/pool_rain/3dgs/seed1
LOG=$WORK/slurm_out/logs/reconstruct/pool_rain_3dgs_seed1.log

echo "== 1. the suite on Slurm; the 3dgs training is cancelled once it has started"
start=$(date +%s)
on_slurm > run1.log 2>&1 &
smk=$!
job=""
for _ in $(seq 1500); do  # up to 5 min (the tiny render comes first)
  job=$(squeue -h -n wgs.reconstruct.pool_rain.3dgs.1 -t RUNNING -o %i | head -n 1)
  if [ -n "$job" ] && grep -q "/300" "$LOG" 2>/dev/null; then break; fi
  job=""
  kill -0 $smk 2> /dev/null || break
  sleep 0.2
done
[ -n "$job" ] || { cat run1.log; fail "the 3dgs training job never ran"; }
scancel "$job"
echo "cancelled Slurm job $job (wgs.reconstruct.pool_rain.3dgs.1) mid-training"
if wait $smk; then cat run1.log; fail "snakemake succeeded although a job was cancelled"; fi
grep -q "Slurm job $job (rule reconstruct, pool_rain 3dgs 1) ended CANCELLED" run1.log || { cat run1.log; fail "no message naming the cancelled cell"; }
[ ! -e "$CELL/results.json" ] || fail "the cancelled cell has a results.json"
[ -e "$WORK/slurm_out/runs/pool_rain/oracle/seed1/results.json" ] || { cat run1.log; fail "the other cell did not finish (keep-going)"; }

echo "== 2. the next invocation reruns the cancelled cell only"
on_slurm > run2.log 2>&1 || { cat run2.log; fail "the second run failed"; }
[ "$(grep -c '^rule reconstruct:' run2.log)" = 1 ] || { cat run2.log; fail "expected exactly one reconstruct job in the second run"; }
! grep -q '^rule generate:' run2.log || fail "the second run generated the data again"
for f in leaderboard.md tables.md curves.csv runs/pool_rain/3dgs/seed1/results.json nerfbaselines/pool_rain/3dgs/seed1/results.json; do
  [ -s "$WORK/slurm_out/$f" ] || fail "missing $f"
done
echo "slurm runs: $(( $(date +%s) - start )) s"

echo "== 3. Slurm's job-completion log: every job COMPLETED except the cancelled one"
ids=$(grep -ho "with external jobid '[0-9]*'" run1.log run2.log | grep -o "[0-9]*" | sort -n)
[ "$(echo "$ids" | wc -l)" -ge 4 ] || fail "expected >= 4 Slurm jobs (generate, 2 reconstruct, the rerun), got: $ids"
for id in $ids; do
  state=$(grep "^JobId=$id " "$CLUSTER/jobcomp.log" | grep -o "JobState=[A-Z_]*" | cut -d= -f2)
  if [ "$id" = "$job" ]; then want=CANCELLED; else want=COMPLETED; fi
  [ "$state" = "$want" ] || fail "Slurm job $id: JobState '$state', expected $want"
  echo "job $id: $state"
done

echo "== 4. a local run on the same generated data: same leaderboard, same model bytes"
mkdir -p local_out
cp -a slurm_out/data local_out/data
snakemake -s "$SRC/workflow/Snakefile" --cores 2 --config out="$WORK/local_out" "${CFG[@]}" > run3.log 2>&1 || { cat run3.log; fail "the local run failed"; }
! grep -q '^rule generate:' run3.log || fail "the local run generated the data again"
cmp slurm_out/leaderboard.md local_out/leaderboard.md || { diff slurm_out/leaderboard.md local_out/leaderboard.md; fail "leaderboards differ"; }
for m in 3dgs oracle; do
  cmp "slurm_out/runs/pool_rain/$m/seed1/model/point_cloud.ply" "local_out/runs/pool_rain/$m/seed1/model/point_cloud.ply" ||
    fail "$m: the Slurm model differs from the local one"
done
cat slurm_out/leaderboard.md

echo "== 5. a memory request that is too small: a clear failure naming the rule and the request"
if on_slurm 'seeds=[2]' 'methods=[3dgs]' 'cluster={mem_scale: 0.02}' > run4.log 2>&1; then cat run4.log; fail "a 30 MB job succeeded"; fi
grep -q "(rule reconstruct, pool_rain 3dgs 2) ended .*: it used more memory than its request of 30M (--mem). Raise mem_mb of rule reconstruct" run4.log ||
  { cat run4.log; fail "no clear out-of-memory message"; }
grep "it used more memory" run4.log

echo "== 6. two concurrent generate jobs on one cache entry: one render"
for k in a b; do
  sbatch --parsable -c 1 --mem=2000M -o "$WORK/gen_$k.out" --wrap "'$WGS' --threads 1 generate --scene '$SRC/scenes/pool.json' \
    --weather snow --profile tiny --max-views 2 --no-colmap --cache '$WORK/cache' --out '$WORK/gen_$k'" > "gen_$k.id"
done
for _ in $(seq 900); do
  [ -z "$(squeue -h -j "$(cat gen_a.id),$(cat gen_b.id)" 2> /dev/null)" ] && break
  sleep 0.2
done
for k in a b; do
  grep -q "JobId=$(cat gen_$k.id) .*JobState=COMPLETED" "$CLUSTER/jobcomp.log" || { cat "gen_$k.out"; fail "generate job $k did not complete"; }
done
renders=$(cat gen_a/dataset.json gen_b/dataset.json | grep -o '"cached": *false' | wc -l)
[ "$renders" = 1 ] || fail "expected one render for two concurrent jobs, got $renders"
cmp gen_a/images/000.png gen_b/images/000.png || fail "the two datasets differ"
grep -h "waiting for another process rendering" gen_a.out gen_b.out || echo "(the second job started after the render: a cache hit without waiting)"
echo "methods/slurm: passed"
