#!/usr/bin/python3
"""workflow/scripts/plot_curves.py: CSV rows and one PNG per variant from curve.json files; a bad
curve is an error naming the file, and leaves no CSV behind. Usage: plot_curves_test.py SOURCE_DIR"""
import csv
import json
import os
import subprocess
import sys
import tempfile

script = os.path.join(sys.argv[1], "workflow", "scripts", "plot_curves.py")


def curve(method, seed, dataset, psnrs):
    pts = [{"iteration": 100 * (i + 1), "train_seconds": 10.0 * (i + 1), "psnr": p, "ssim": 0.5, "lpips": 0.3,
            "num_gaussians": 1000} for i, p in enumerate(psnrs)]
    return {"format": "weathergs-curve", "version": 1, "method": method, "dataset": dataset, "scene": "pool",
            "weather": "rain", "seed": seed, "points": pts}


with tempfile.TemporaryDirectory() as tmp:
    files = []
    for i, (m, s, d, p) in enumerate([("3dgs", 0, "pool_rain", [20, 22]), ("3dgs", 1, "pool_rain", [21, 23]),
                                      ("oracle", 0, "pool_rain", [25, 30]), ("3dgs", 0, "pool_snow", [19, 24])]):
        files.append(os.path.join(tmp, f"c{i}.json"))
        with open(files[-1], "w") as f:
            json.dump(curve(m, s, d, p), f)
    out_csv, png_dir = os.path.join(tmp, "curves.csv"), os.path.join(tmp, "curves")
    r = subprocess.run(["/usr/bin/python3", script, "--csv", out_csv, "--png-dir", png_dir] + files,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    rows = list(csv.DictReader(open(out_csv)))
    assert len(rows) == 8, rows
    assert rows[0]["variant"] == "pool_rain" and rows[0]["method"] == "3dgs" and rows[0]["seed"] == "0", rows[0]
    assert float(rows[-1]["psnr"]) == 24 and rows[-1]["variant"] == "pool_snow", rows[-1]
    for v in ("pool_rain", "pool_snow"):
        with open(os.path.join(png_dir, v + ".png"), "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n", v
    # A curve of another format: exit != 0, the file named, no CSV written.
    bad = os.path.join(tmp, "bad.json")
    with open(bad, "w") as f:
        json.dump({"format": "weathergs-results"}, f)
    out2 = os.path.join(tmp, "none.csv")
    r = subprocess.run(["/usr/bin/python3", script, "--csv", out2, "--png-dir", png_dir, bad],
                       capture_output=True, text=True)
    assert r.returncode != 0 and "bad.json" in r.stderr, (r.returncode, r.stderr)
    assert not os.path.exists(out2)
print("ok")
