#!/usr/bin/python3
"""Snakemake's --cluster-status command for Slurm (docs/cluster.md): prints running, success or
failed for a job id. Reads `scontrol show job` (works without accounting; Slurm forgets a finished job
after MinJobAge, 300 s by default, far longer than Snakemake's polling interval), then `sacct` where
accounting exists. When a job failed it says why on stderr, once, naming the rule, the cell and the
request that was exceeded, so that the fix (a larger mem_mb or runtime in workflow/config.yaml's
`cluster` section) is obvious."""
import os
import subprocess
import sys

RUNNING = {"PENDING", "CONFIGURING", "RUNNING", "COMPLETING", "SUSPENDED", "REQUEUED", "REQUEUE_FED",
           "REQUEUE_HOLD", "RESIZING", "SIGNALING", "STAGE_OUT", "RESV_DEL_HOLD", "STOPPED", "PREEMPTED"}


def scontrol(jobid):
    r = subprocess.run(["scontrol", "show", "job", "-o", jobid], stdout=subprocess.PIPE,
                       stderr=subprocess.DEVNULL, text=True)
    if r.returncode != 0 or not r.stdout.strip():
        return None
    fields = {}
    for token in r.stdout.split():
        key, sep, value = token.partition("=")
        if sep and key not in fields:
            fields[key] = value
    return fields


def sacct(jobid):
    r = subprocess.run(["sacct", "-n", "-X", "-P", "-j", jobid, "-o", "State,JobName,ReqMem,ExitCode,Timelimit"],
                       stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    line = r.stdout.strip().splitlines()[0] if r.returncode == 0 and r.stdout.strip() else ""
    if not line:
        return None
    state, name, mem, code, limit = (line.split("|") + [""] * 5)[:5]
    return {"JobState": state.split()[0], "JobName": name, "MinMemoryNode": mem, "ExitCode": code, "TimeLimit": limit}


def explain(jobid, job):
    state = job.get("JobState", "?")
    name = job.get("JobName", "?")
    parts = name.split(".")
    rule = parts[1] if len(parts) > 1 and parts[0] == "wgs" else name
    cell = " ".join(parts[2:])
    out = job.get("StdOut", "")
    log = ""
    if out and os.path.isfile(out):
        with open(out, errors="replace") as f:
            log = f.read()[-20000:]
    what = "Slurm job %s (rule %s%s) ended %s, exit code %s" % (jobid, rule, ", " + cell if cell else "", state,
                                                              job.get("ExitCode", "?"))
    if state == "OUT_OF_MEMORY" or "exceeded memory limit" in log.lower() or "exceeded job memory limit" in log.lower():
        what += (": it used more memory than its request of %s (--mem). Raise mem_mb of rule %s for this profile "
                 "in the config's `cluster` section, or cluster.mem_scale" % (job.get("MinMemoryNode", "?"), rule))
    elif state in ("TIMEOUT", "DEADLINE"):
        what += (": it ran past its time request of %s. Raise runtime of rule %s for this profile in the config's "
                 "`cluster` section" % (job.get("TimeLimit", "?"), rule))
    elif state == "CANCELLED":
        what += ": cancelled (scancel, or the node went away); the next snakemake run resubmits it"
    if out:
        what += ". Slurm's output: " + out
    sys.stderr.write(what + "\n")


def main():
    if len(sys.argv) != 2:
        sys.stderr.write("usage: status.py JOBID\n")
        return 2
    jobid = sys.argv[1].split(";")[0]
    job = scontrol(jobid) or sacct(jobid)
    if job is None:
        sys.stderr.write("Slurm job %s: unknown to scontrol and sacct (finished longer than MinJobAge ago on a "
                         "cluster without accounting?); counted as failed\n" % jobid)
        print("failed")
        return 0
    state = job.get("JobState", "")
    if state in RUNNING:
        print("running")
    elif state == "COMPLETED":
        print("success")
    else:
        explain(jobid, job)
        print("failed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
