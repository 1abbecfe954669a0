#!/usr/bin/python3
"""benchmarks/experiments/carryover/summary.py: a layout's gain and oracle-gap share set beside the
archive's rain variants; a cell not yet archived or run is said, not guessed; a bad record is an error
naming the file (exit 2). Usage: carryover_summary_test.py SOURCE_DIR"""
import json
import os
import subprocess
import sys
import tempfile

script = os.path.join(sys.argv[1], "benchmarks", "experiments", "carryover", "summary.py")
PSNR = {"3dgs": 20.0, "weathergs": 25.0, "gt-masks": 26.0, "oracle": 30.0}


def write(path, obj):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        json.dump(obj, f)


def result(method, psnr, warnings=()):
    return {"metrics": {"psnr": psnr, "ssim": 0.8, "lpips": 0.2}, "method_info": {"warnings": list(warnings)}}


def run(tmp):
    return subprocess.run(["/usr/bin/python3", script, f"{tmp}/carry", f"{tmp}/archive", f"{tmp}/bench",
                           "carry_a:00:1.8:1.0", "carry_b:01:8.0:10.0"], capture_output=True, text=True)


failures = []
with tempfile.TemporaryDirectory() as tmp:
    # Benchmark: pool_rain and factory_rain archived (gain 5 of a 10 dB gap: 50 %); tanabata_rain lacks its oracle.
    for v in ("pool_rain", "factory_rain", "tanabata_rain"):
        for m, p in PSNR.items():
            if not (v == "tanabata_rain" and m == "oracle"):
                write(f"{tmp}/archive/{v}/{m}/seed0/results.json", result(m, p))
    write(f"{tmp}/bench/pool_rain/weathergs/seed0/detected/detect.json",
          {"ground_truth": {"iou": 0.67, "precision": 0.84}})
    # carry_a: gain 2 dB of a 8 dB gap (25 %), the warning fired; carry_b has no oracle yet.
    for m, p in {"3dgs": 22.0, "weathergs": 24.0, "gt-masks": 25.0, "oracle": 30.0}.items():
        write(f"{tmp}/carry/runs/carry_a_wet/{m}/results.json",
              result(m, p, ["the LED masked almost nothing"] if m == "weathergs" else ()))
    write(f"{tmp}/carry/runs/carry_a_wet/weathergs/detected/detect.json",
          {"ground_truth": {"iou": 0.3, "precision": 0.9}})
    for m in ("3dgs", "weathergs", "gt-masks"):
        write(f"{tmp}/carry/runs/carry_b_wet/{m}/results.json", result(m, PSNR[m]))
    r = run(tmp)
    out = r.stdout
    expect = ["| benchmark pool_rain (f/2.8, focus 2 m) | 20.00 / 0.800 / 0.200 |", "| +5.00 dB | 50% of 10.00 dB | 0.670 / 0.840 | no |",
              "| benchmark factory_rain (f/2.8, focus 2 m) |", "| n/a | no |",  # no run folder: LED n/a
              "| benchmark tanabata_rain | not archived yet: oracle |",
              "| carry_a (f/1.8, focus 1.0 m) |", "| +2.00 dB | 25% of 8.00 dB | 0.300 / 0.900 | yes: the LED masked almost nothing |",
              "| carry_b | not run yet: oracle |",
              "mean gain +5.00 dB, mean share of the oracle's gap 50%",
              "carry_a keeps 40% of the mean gain (+2.00 dB) and has 25% of its oracle's gap against the benchmark's 50%"]
    if r.returncode != 0:
        failures.append(f"exit {r.returncode}: {r.stderr}")
    failures += [f"missing {e!r}" for e in expect if e not in out]
    with open(f"{tmp}/carry/runs/carry_a_wet/oracle/results.json", "w") as f:
        f.write("{")
    r = run(tmp)
    if r.returncode != 2 or "carry_a_wet/oracle/results.json" not in r.stderr:
        failures.append(f"a broken record must fail naming it (exit 2): exit {r.returncode}, {r.stderr!r}")
if failures:
    print("\n".join(failures) + "\n--- output:\n" + out)
    sys.exit(1)
print("ok")
