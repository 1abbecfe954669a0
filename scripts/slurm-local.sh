#!/usr/bin/env bash
# A real one-node Slurm cluster on this machine, every file under one folder, for tests and trials of
# the cluster profile (docs/cluster.md):
#   scripts/slurm-local.sh start DIR [CPUS] [MEMORY_MB]   writes DIR/slurm.conf, starts munged,
#                                                        slurmctld and slurmd; prints the SLURM_CONF to export
#   scripts/slurm-local.sh stop DIR                       stops the three daemons (by their pid files)
# Needs root (slurmd launches jobs as their user) and Debian's slurm-wlm + munge
# (`scripts/install-deps.sh slurm`). Munge gets its own socket: the packaged /run/munge setup refuses
# to start here (log-file ownership). Accounting is off; finished jobs are recorded in the job
# completion log DIR/jobcomp.log. Memory requests are enforced by polling (jobacct_gather/linux with
# OverMemoryKill, every second), as a cgroup-less stand-in for a production cluster's task/cgroup.
set -euo pipefail

usage() { echo "usage: $0 start DIR [CPUS] [MEMORY_MB] | stop DIR" >&2; exit 2; }
[ $# -ge 2 ] || usage
cmd=$1
dir=$(mkdir -p "$2" && cd "$2" && pwd)

stop() {
  local name pid
  for name in slurmd slurmctld munged; do
    [ -f "$dir/$name.pid" ] || continue
    pid=$(cat "$dir/$name.pid" 2>/dev/null || true)
    if [ -n "$pid" ] && kill -0 "$pid" 2>/dev/null; then
      kill "$pid" 2>/dev/null || true
      for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
      kill -9 "$pid" 2>/dev/null || true
    fi
    rm -f "$dir/$name.pid"
  done
}

case "$cmd" in
  stop) stop; exit 0 ;;
  start) ;;
  *) usage ;;
esac

cpus=${3:-$(nproc)}
mem=${4:-$(( $(awk '/MemTotal/ {print int($2 / 1024)}' /proc/meminfo) * 3 / 4 ))}
for tool in munged slurmctld slurmd sbatch; do
  command -v "$tool" >/dev/null 2>&1 || { echo "$0: $tool not found: run scripts/install-deps.sh slurm" >&2; exit 77; }
done
[ "$(id -u)" = 0 ] || { echo "$0: needs root (slurmd starts jobs as their user)" >&2; exit 77; }
[ -r /etc/munge/munge.key ] || { echo "$0: /etc/munge/munge.key missing (reinstall munge)" >&2; exit 77; }

# Private ports so that two clusters (or a system Slurm) can coexist: derived from the folder.
base=$(( 20000 + $(printf '%s' "$dir" | cksum | cut -d' ' -f1) % 20000 ))
host=$(hostname -s)
mkdir -p "$dir/state" "$dir/spool" "$dir/log"
cat > "$dir/slurm.conf" <<CONF
ClusterName=weathergs-local
SlurmctldHost=$host
SlurmUser=root
SlurmctldPort=$base
SlurmdPort=$(( base + 1 ))
AuthType=auth/munge
AuthInfo=socket=$dir/munge.sock
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SwitchType=switch/none
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
AccountingStorageType=accounting_storage/none
JobAcctGatherType=jobacct_gather/linux
JobAcctGatherFrequency=task=1
JobAcctGatherParams=OverMemoryKill
JobCompType=jobcomp/filetxt
JobCompLoc=$dir/jobcomp.log
MinJobAge=600
KillWait=10
SlurmctldTimeout=30
SlurmdTimeout=30
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=main Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF

stop
munged --force --socket="$dir/munge.sock" --key-file=/etc/munge/munge.key --log-file="$dir/log/munged.log" \
  --pid-file="$dir/munged.pid" --seed-file="$dir/munge.seed"
export SLURM_CONF=$dir/slurm.conf
slurmctld -f "$SLURM_CONF"
slurmd -f "$SLURM_CONF"
for _ in $(seq 100); do
  if sinfo -h -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then
    echo "export SLURM_CONF=$SLURM_CONF"
    exit 0
  fi
  sleep 0.2
done
echo "$0: the node did not come up in 20 s; logs in $dir/log:" >&2
tail -n 20 "$dir/log/"*.log >&2 || true
stop
exit 1
