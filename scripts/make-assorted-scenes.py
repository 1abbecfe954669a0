#!/usr/bin/python3
"""Writes N scene specs of the randomized training type "assorted" (blender_scripts/weathergs_blender/
layouts/assorted.py): OUT/assorted_NN.json for NN = 00..N-1, each drawn from (SEED, NN) alone, so the
set is deterministic and a larger N keeps the first specs. Each draws its layout seed, its materials
(pattern, colours, scale) from the generic material names the layout uses, its sky and sun (clear,
hazy-warm or overcast), and a camera path like the other training scenes' with a random heading and
pitch; its `wet` and `snowy` variants put rain or snow on the ground under an overcast sky.
Training scenes of the restoration part only (scripts/make-training-data.sh, ASSORTED_SCENES): never
the benchmark's.

    scripts/make-assorted-scenes.py N OUT [SEED=1]
"""
import colorsys
import json
import os
import random
import sys

PATTERNS = {  # material -> the patterns it draws from
    "ground": ["noise", "tiles", "voronoi", "foliage"],
    "ground2": ["noise", "tiles", "voronoi", "water", "foliage"],
    "wall0": ["noise", "brick", "tiles", "wave"],
    "wall1": ["noise", "brick", "tiles", "wave"],
    "wall2": ["noise", "brick", "metal", "wave"],
    "wall3": ["noise", "tiles", "metal", "voronoi"],
    "metal0": ["metal"],
    "metal1": ["metal", "noise"],
    "accent0": ["noise", "metal"],
    "accent1": ["noise", "wave"],
    "foliage": ["foliage"],
    "bark": ["wave", "noise"],
    "window": ["noise"],
}


def colour(rng, saturation, value):
    h = rng.random()
    s = rng.uniform(*saturation)
    v = rng.uniform(*value)
    return [round(c, 3) for c in colorsys.hsv_to_rgb(h, s, v)]


def material(rng, name):
    pattern = rng.choice(PATTERNS[name])
    if name == "foliage":
        base = colour(rng, (0.4, 0.8), (0.15, 0.45))
        base = [round(base[0] * 0.6, 3), base[1], round(base[2] * 0.5, 3)]  # greenish
    elif name == "window":
        base = colour(rng, (0.0, 0.3), (0.1, 0.4))
    elif name.startswith("accent"):
        base = colour(rng, (0.5, 0.95), (0.3, 0.9))
    elif name.startswith("metal"):
        base = colour(rng, (0.0, 0.25), (0.1, 0.8))
    else:
        base = colour(rng, (0.0, 0.5), (0.1, 0.85))
    k = rng.uniform(0.55, 0.9)
    m = {"pattern": pattern, "color": base, "color2": [round(c * k, 3) for c in base],
         "scale_m": round(rng.uniform(0.05, 1.5), 3), "roughness": round(rng.uniform(0.2, 0.95), 2)}
    if pattern == "water":
        m.update(roughness=0.05, bump=0.2, color=colour(rng, (0.3, 0.7), (0.05, 0.2)))
        m["color2"] = [round(c * 1.3, 3) for c in m["color"]]
    if pattern in ("brick", "tiles"):
        m["mortar_color"] = colour(rng, (0.0, 0.15), (0.35, 0.7))
    if pattern == "brick" or (name.startswith("wall") and pattern in ("wave", "noise")):
        m["axes"] = "xz"
    if pattern == "metal":
        m["metallic"] = round(rng.uniform(0.3, 0.9), 2)
    if name.startswith(("ground", "wall", "bark")):
        m["porosity"] = round(rng.uniform(0.2, 0.8), 2)
    return m


def overcast(rng):
    g = rng.uniform(0.45, 0.92)
    tint = [rng.uniform(-0.04, 0.04) for _ in range(3)]
    horizon = [round(min(1.0, g + t), 3) for t in tint]
    zenith = [round(c * rng.uniform(0.8, 1.0), 3) for c in horizon]
    return ({"strength": round(rng.uniform(0.2, 0.7), 2), "angle_deg": round(rng.uniform(12, 25), 1)},
            {"horizon_color": horizon, "zenith_color": zenith, "strength": round(rng.uniform(0.9, 1.3), 2)})


def lights(rng):
    kind = rng.random()
    sun = {"color": [1.0, 0.96, 0.9], "elevation_deg": round(rng.uniform(15, 60), 1),
           "azimuth_deg": round(rng.uniform(0, 360), 1), "angle_deg": 2.0, "strength": round(rng.uniform(2.5, 4.0), 2)}
    if kind < 0.4:  # clear
        sky = {"horizon_color": [round(rng.uniform(0.62, 0.8), 3), round(rng.uniform(0.72, 0.85), 3), round(rng.uniform(0.85, 0.95), 3)],
               "zenith_color": [round(rng.uniform(0.22, 0.45), 3), round(rng.uniform(0.38, 0.55), 3), round(rng.uniform(0.72, 0.9), 3)],
               "strength": round(rng.uniform(0.8, 1.2), 2)}
    elif kind < 0.6:  # hazy, low warm sun
        sun.update(elevation_deg=round(rng.uniform(5, 20), 1), strength=round(rng.uniform(1.0, 2.5), 2), color=[1.0, 0.82, 0.65])
        sky = {"horizon_color": [round(rng.uniform(0.8, 0.95), 3), round(rng.uniform(0.6, 0.75), 3), round(rng.uniform(0.5, 0.6), 3)],
               "zenith_color": [round(rng.uniform(0.3, 0.45), 3), round(rng.uniform(0.35, 0.45), 3), round(rng.uniform(0.55, 0.7), 3)],
               "strength": round(rng.uniform(0.8, 1.2), 2)}
    else:  # overcast, dry
        s, sky = overcast(rng)
        sun.update(s)
    return {"sun": sun, "sky": sky}


def scene(seed, index):
    rng = random.Random(f"assorted-{seed}-{index}")
    name = f"assorted_{index:02d}"
    heading = rng.uniform(-8.0, 8.0)
    wet_sun, wet_sky = overcast(rng)
    snow_sun, snow_sky = overcast(rng)
    return name, {
        "name": name,
        "type": "assorted",
        "description": "A randomized street of mixed structure (scripts/make-assorted-scenes.py, seed "
                       f"{seed}, index {index}). A training scene of the restoration part: never part of the benchmark.",
        "seed": rng.randrange(1 << 31),
        "layout": {"depth_m": round(rng.uniform(30.0, 90.0), 1), "clutter_count": rng.randint(6, 24)},
        "materials": {n: material(rng, n) for n in sorted(PATTERNS)},
        "lights": lights(rng),
        "camera": {"position_m": [round(rng.uniform(-1.5, 1.5), 2), -3.0, round(rng.uniform(1.4, 2.2), 2)],
                   "look_at_m": [round(heading, 2), 18.0, round(rng.uniform(0.3, 4.0), 2)],
                   "radius_m": [1.2, 0.45], "depth_m": 0.8, "turns": 2.0, "focal_length_mm": 4.0,
                   "sensor_width_mm": 6.0, "f_number": 2.8, "focus_distance_m": 2.0, "exposure_s": 0.0167,
                   "frame_interval_s": 0.5},
        "profiles": {"tiny": {"width": 192, "height": 128, "views": 5, "samples": 4},
                     "quick": {"width": 300, "height": 200, "views": 16, "samples": 8},
                     "paper": {"width": 600, "height": 400, "views": 34, "samples": 32}},
        "split": {"rule": "llff", "every": 8},
        "variants": {
            "wet": {"surface": {"kind": "rain", "wetness": round(rng.uniform(0.5, 0.9), 2), "darkening": round(rng.uniform(0.3, 0.5), 2),
                                "puddle_coverage": round(rng.uniform(0.1, 0.4), 2), "puddle_scale_m": 2.0},
                    "lights": {"sun": wet_sun, "sky": wet_sky}},
            "snowy": {"surface": {"kind": "snow", "coverage": round(rng.uniform(0.3, 0.7), 2), "normal_threshold": 0.5,
                                  "noise_scale_m": 1.5},
                      "lights": {"sun": snow_sun, "sky": snow_sky}},
        },
    }


def main():
    if len(sys.argv) not in (3, 4):
        sys.exit("usage: make-assorted-scenes.py N OUT [SEED]")
    n, out = int(sys.argv[1]), sys.argv[2]
    seed = int(sys.argv[3]) if len(sys.argv) == 4 else 1
    if not 1 <= n <= 100:
        sys.exit(f"make-assorted-scenes: N must be 1..100, got {n}")
    os.makedirs(out, exist_ok=True)
    for i in range(n):
        name, spec = scene(seed, i)
        path = os.path.join(out, name + ".json")
        tmp = path + ".tmp"
        with open(tmp, "w") as f:
            json.dump(spec, f, indent=1)
            f.write("\n")
        os.replace(tmp, path)
        print(path)


if __name__ == "__main__":
    main()
