#!/usr/bin/python3
"""Checks a `weathergs export-nerfbaselines` folder the way NerfBaselines reads it.

Re-implements, from nerfbaselines/io.py (get_predictions_sha, _encode_values, get_metrics_hash), the
hashes and encodings of an evaluation results file, and compares them with the export and with the
weathergs results.json it came from. Usage: nerfbaselines_reference.py EXPORT_DIR WEATHERGS_RESULTS.
Exit 0 when everything matches; prints the first mismatch and exits 1 otherwise."""
import base64
import hashlib
import json
import pathlib
import struct
import sys


def predictions_sha(root):
    pred, gt = hashlib.sha256(), hashlib.sha256()
    names = sorted(p.relative_to(root / "color") for p in (root / "color").glob("**/*") if p.is_file())
    for name in names:
        pred.update((root / "color" / name).read_bytes())
        gt.update((root / "gt-color" / name).read_bytes())
    return pred.hexdigest(), gt.hexdigest(), [str(n) for n in names]


def encode(values):
    return base64.b64encode(b"".join(struct.pack("<f", v) for v in values)).decode("ascii")


def decode(text):
    raw = base64.b64decode(text)
    return [struct.unpack("<f", raw[i:i + 4])[0] for i in range(0, len(raw), 4)]


def metrics_sha(lists):
    sha = hashlib.sha256()
    for key in sorted(lists):
        sha.update(key.lower().encode("utf8"))
        sha.update(encode(sorted(lists[key])).encode("ascii"))
        sha.update(b"\n")
    return sha.hexdigest()


def main():
    export, ours = pathlib.Path(sys.argv[1]), json.loads(pathlib.Path(sys.argv[2]).read_text())
    nb = json.loads((export / "results.json").read_text())
    info = json.loads((export / "predictions" / "info.json").read_text())
    pred, gt, names = predictions_sha(export / "predictions")
    checks = [("predictions_sha256", nb["predictions_sha256"], pred),
              ("ground_truth_sha256", nb["ground_truth_sha256"], gt),
              ("evaluation_protocol", nb["evaluation_protocol"], info["evaluation_protocol"]),
              ("method", nb["nb_info"]["method"], ours["method"])]
    per_view = ours["per_view"]  # {view: {"psnr", "ssim", "lpips"}}
    expected_names = sorted(v + ".png" for v in per_view)
    checks.append(("file names", names, expected_names))
    lists = {k: decode(v) for k, v in nb["metrics_raw"].items()}
    checks.append(("metrics_sha256", nb["metrics_sha256"], metrics_sha(lists)))
    for key, values in lists.items():
        want = [per_view[n[:-4]][key] for n in names]  # per_view entries hold psnr / ssim / lpips
        got_ok = all(abs(a - b) <= 1e-5 * max(1.0, abs(b)) for a, b in zip(values, want))
        checks.append((f"metrics_raw.{key} vs weathergs per_view", got_ok and len(values) == len(want), True))
        mean = sum(values) / len(values)
        checks.append((f"metrics.{key} is the mean", abs(nb["metrics"][key] - mean) <= 1e-4, True))
    for name, got, want in checks:
        if got != want:
            print(f"MISMATCH {name}: export has {got!r}, expected {want!r}")
            return 1
    print(f"ok: {len(names)} views, metrics {nb['metrics']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
