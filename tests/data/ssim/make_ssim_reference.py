#!/usr/bin/python3
"""Generates the SSIM test pairs and their reference values (run once; outputs are committed).

Reference implementations:
  valid: skimage.metrics.structural_similarity(a, b, channel_axis=2, data_range=1.0,
         gaussian_weights=True, sigma=1.5, use_sample_covariance=False)   (scikit-image 0.19.3)
  same:  the 3DGS formula (11x11 Gaussian, sigma 1.5, zero padding, mean of the map), computed with
         scipy.ndimage.correlate(mode='constant', cval=0), which equals torch's F.conv2d(padding=5)
         for this symmetric window.
Images are 8-bit RGB PNGs; values are scored as uint8 / 255 in float64.
Usage: /usr/bin/python3 make_ssim_reference.py   (from this folder)
"""
import json

import numpy as np
from PIL import Image
from scipy import ndimage
from skimage.metrics import structural_similarity


def gaussian_window(sigma=1.5, radius=5):
    x = np.arange(-radius, radius + 1, dtype=np.float64)
    g = np.exp(-(x ** 2) / (2 * sigma ** 2))
    g /= g.sum()
    return np.outer(g, g)


def ssim_same(a, b):
    w = gaussian_window()
    c1, c2 = 0.01 ** 2, 0.03 ** 2
    vals = []
    for c in range(a.shape[2]):
        x, y = a[..., c], b[..., c]
        f = lambda im: ndimage.correlate(im, w, mode="constant", cval=0.0)
        mx, my = f(x), f(y)
        vx, vy, cxy = f(x * x) - mx * mx, f(y * y) - my * my, f(x * y) - mx * my
        m = ((2 * mx * my + c1) * (2 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2))
        vals.append(m.mean())
    return float(np.mean(vals))


def make_pairs(rng):
    pairs = {}
    h, w = 40, 48
    yy, xx = np.mgrid[0:h, 0:w] / 10.0
    base = np.stack([0.5 + 0.4 * np.sin(xx + c) * np.cos(yy * 0.7 + c) for c in range(3)], axis=2)
    pairs["smooth_noise"] = (base, np.clip(base + rng.normal(0, 0.05, base.shape), 0, 1))
    pairs["random"] = (rng.random((33, 29, 3)), rng.random((33, 29, 3)))
    blur = ndimage.uniform_filter(base, size=(3, 3, 1))
    pairs["blur"] = (base, blur)
    big = rng.random((97, 131, 3))
    pairs["odd_97x131"] = (big, np.clip(big * 0.8 + 0.1 + rng.normal(0, 0.02, big.shape), 0, 1))
    const = np.full((20, 20, 3), 0.4)
    pairs["constant_vs_constant"] = (const, np.full((20, 20, 3), 0.6))
    return pairs


def main():
    rng = np.random.default_rng(20261122)
    out = {"description": __doc__.strip().splitlines()[0], "pairs": {}}
    for name, (a, b) in make_pairs(rng).items():
        a8 = np.round(a * 255).astype(np.uint8)
        b8 = np.round(b * 255).astype(np.uint8)
        Image.fromarray(a8).save(f"{name}_a.png")
        Image.fromarray(b8).save(f"{name}_b.png")
        af, bf = a8.astype(np.float64) / 255, b8.astype(np.float64) / 255
        valid = structural_similarity(af, bf, channel_axis=2, data_range=1.0, gaussian_weights=True,
                                      sigma=1.5, use_sample_covariance=False)
        mse = float(np.mean((af - bf) ** 2))
        out["pairs"][name] = {"a": f"{name}_a.png", "b": f"{name}_b.png", "height": a8.shape[0],
                              "width": a8.shape[1], "ssim_valid": float(valid),
                              "ssim_same": ssim_same(af, bf),
                              "psnr": float(10 * np.log10(1.0 / mse)) if mse > 0 else None}
    with open("ssim_reference.json", "w") as f:
        json.dump(out, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
