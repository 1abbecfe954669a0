#!/usr/bin/python3
"""Snakemake's --cluster submit command for Slurm (docs/cluster.md): one sbatch per job, with the
job's threads, memory (resources.mem_mb) and time (resources.runtime, minutes) as declared per rule in
workflow/Snakefile, a job name that says which cell it is (wgs.<rule>.<wildcards>) and Slurm's own
output next to the rule's log (<log>.slurm-<jobid>.out). Site options (partition, account, QOS) come
from $WEATHERGS_SBATCH_ARGS, e.g. "--partition=cpu --account=vision". Prints the job id."""
import os
import shlex
import subprocess
import sys

from snakemake.utils import read_job_properties


def main():
    jobscript = sys.argv[-1]
    job = read_job_properties(jobscript)
    rule = job.get("rule") or "group." + str(job.get("groupid", "job"))
    name = ".".join(["wgs", rule] + [str(v) for v in job.get("wildcards", {}).values()])
    resources = job.get("resources", {})
    args = ["sbatch", "--parsable", "--job-name=" + name, "--cpus-per-task=%d" % int(job.get("threads", 1))]
    if "mem_mb" in resources:
        args.append("--mem=%dM" % int(resources["mem_mb"]))
    if "runtime" in resources:
        args.append("--time=%d" % int(resources["runtime"]))
    logs = job.get("log") or []
    out = logs[0] + ".slurm-%j.out" if logs else os.path.join("slurm-logs", name + ".%j.out")
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)  # sbatch does not create it
    args.append("--output=" + out)
    args += shlex.split(os.environ.get("WEATHERGS_SBATCH_ARGS", ""))
    args.append(jobscript)
    r = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        sys.stderr.write("sbatch refused rule %s (%s):\n%s" % (rule, " ".join(map(shlex.quote, args)), r.stderr))
        return r.returncode
    print(r.stdout.strip().split(";")[0])  # "jobid" or "jobid;cluster"
    return 0


if __name__ == "__main__":
    sys.exit(main())
