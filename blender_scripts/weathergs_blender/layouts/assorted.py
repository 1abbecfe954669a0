"""Scene type "assorted" (a training scene of the restoration part, never a benchmark scene): a
randomized street of mixed structure, drawn from the spec's seed, so that many seeds give the lens-drop
detector backgrounds it has not learned by heart (docs/record/led_scenes.md).
Every draw mixes buildings at several depths, thin structure against the sky (poles, lattice frames,
cables, fences), rounded things (tanks, trees) and clutter near the camera. Its materials are the
spec's generic ones (ground, ground2, wall0..wall3, metal0, metal1, accent0, accent1, foliage, bark,
window), which scripts/make-assorted-scenes.py draws per scene. The camera looks roughly along +y."""
import math


def _lattice(b, rng, material, x, y, width, height, along_x):
    """A frame of posts and horizontal beams (a gantry, a scaffold, a truss) in one vertical plane."""
    posts = rng.randint(2, 5)
    t = rng.uniform(0.12, 0.45)
    for i in range(posts):
        u = -width / 2 + i * width / (posts - 1)
        px, py = (x + u, y) if along_x else (x, y + u)
        b.box(material, (t, t, height), (px, py, height / 2), name="post")
    beams = rng.randint(1, 4)
    for j in range(beams):
        z = height * (1.0 - j * rng.uniform(0.18, 0.32))
        size = (width, t * 0.8, t * 0.8) if along_x else (t * 0.8, width, t * 0.8)
        b.box(material, size, (x, y, z), name="beam")
    if rng.random() < 0.5:  # a diagonal brace
        angle = math.atan2(height * 0.6, width)
        rot = (0, -angle, 0) if along_x else (angle, 0, 0)
        size = (math.hypot(width, height * 0.6), t * 0.6, t * 0.6) if along_x else (t * 0.6, math.hypot(width, height * 0.6), t * 0.6)
        b.box(material, size, (x, y, height * 0.45), rot, name="brace")


def build(b, p, rng):
    depth = p.num("depth_m", 50.0, 15.0, 300.0)
    clutter = p.int("clutter_count", 14, 0, 200)
    p.finish()
    walls = ["wall0", "wall1", "wall2", "wall3"]
    metals = ["metal0", "metal1"]
    b.box("ground", (90.0, depth + 60, 0.2), (0, depth / 2, -0.1), name="ground")
    # A strip of the second ground material (a road, a canal bank, a lawn) along the view.
    w2 = rng.uniform(3.0, 10.0)
    b.box("ground2", (w2, depth + 40, 0.04), (rng.uniform(-4.0, 4.0), depth / 2, 0.02), name="strip")
    # Buildings on either side, at random setbacks, and sometimes a backdrop across the end.
    for side in (-1, 1):
        if rng.random() < 0.2:
            continue  # this side open: more sky and distance
        y = rng.uniform(-2.0, 6.0)
        while y < depth:
            w, d, h = rng.uniform(4.0, 12.0), rng.uniform(4.0, 14.0), rng.uniform(3.0, 24.0)
            x = side * (rng.uniform(5.0, 14.0) + w / 2)
            b.box(rng.choice(walls), (w, d, h), (x, y + d / 2, h / 2), name="building")
            if rng.random() < 0.6:  # a row of windows on the face towards the street
                for k in range(int(d / 3.0)):
                    for z in range(int((h - 1.0) / 3.5)):
                        b.box("window", (0.06, 1.2, 1.4), (x - side * (w / 2 + 0.03), y + 1.5 + 3.0 * k, 2.0 + 3.5 * z),
                              name="window")
            if rng.random() < 0.3:  # a flat roof slab with an overhang
                b.box(rng.choice(metals + walls), (w + 0.8, d + 0.8, 0.3), (x, y + d / 2, h + 0.15), name="roof")
            y += d + rng.uniform(0.5, 8.0)
    if rng.random() < 0.5:
        h = rng.uniform(6.0, 30.0)
        b.box(rng.choice(walls), (60.0, 3.0, h), (rng.uniform(-10, 10), depth + rng.uniform(0, 30), h / 2), name="backdrop")
    # Thin structure against the sky: poles and masts, lattice frames, cables between poles.
    poles = []
    for i in range(rng.randint(3, 10)):
        x, y = rng.choice((-1, 1)) * rng.uniform(2.5, 12.0), rng.uniform(3.0, depth)
        h = rng.uniform(3.0, 16.0)
        b.cylinder(rng.choice(metals), rng.uniform(0.05, 0.25), h, (x, y, h / 2), segments=10, name="pole")
        if rng.random() < 0.4:  # an arm or a lamp head
            b.box(rng.choice(metals), (rng.uniform(0.8, 3.0), 0.12, 0.12), (x - math.copysign(0.8, x), y, h - 0.1), name="arm")
        poles.append((x, y, h))
    for i in range(1, len(poles)):
        (x0, y0, h0), (x1, y1, h1) = poles[i - 1], poles[i]
        if rng.random() < 0.5:
            continue
        z = min(h0, h1) - 0.3
        length = math.hypot(x1 - x0, y1 - y0)
        yaw = math.atan2(y1 - y0, x1 - x0)
        b.box(rng.choice(metals), (length, 0.03, 0.03), ((x0 + x1) / 2, (y0 + y1) / 2, z), (0, 0, yaw), name="cable")
    for i in range(rng.randint(1, 4)):
        along_x = rng.random() < 0.6
        x, y = rng.uniform(-8.0, 8.0), rng.uniform(6.0, depth * 0.8)
        _lattice(b, rng, rng.choice(metals + ["accent0"]), x, y, rng.uniform(4.0, 16.0), rng.uniform(3.0, 14.0), along_x)
    if rng.random() < 0.6:  # a fence along one side of the street
        side = rng.choice((-1, 1))
        fx = side * rng.uniform(2.0, 5.0)
        spacing = rng.uniform(0.15, 2.5)
        fh = rng.uniform(0.8, 2.5)
        material = rng.choice(metals + ["bark", "accent1"])
        for k in range(int(min(depth, 40.0) / spacing)):
            b.box(material, (0.05, 0.05, fh), (fx, 1.0 + k * spacing, fh / 2), name="fence_post")
        for z in (fh * 0.4, fh * 0.9):
            b.box(material, (0.04, min(depth, 40.0), 0.05), (fx, 1.0 + min(depth, 40.0) / 2, z), name="fence_rail")
    # Rounded things: tanks and trees.
    for i in range(rng.randint(0, 4)):
        r, h = rng.uniform(1.0, 5.0), rng.uniform(2.0, 12.0)
        b.cylinder(rng.choice(metals + walls), r, h, (rng.choice((-1, 1)) * rng.uniform(8.0, 20.0), rng.uniform(8.0, depth), h / 2),
                   segments=24, name="tank")
    for i in range(rng.randint(0, 10)):
        x, y = rng.choice((-1, 1)) * rng.uniform(3.0, 20.0), rng.uniform(2.0, depth)
        h = rng.uniform(2.0, 6.0)
        b.cylinder("bark", rng.uniform(0.1, 0.3), h, (x, y, h / 2), segments=8, name="trunk")
        r = rng.uniform(1.0, 3.5)
        b.sphere("foliage", r, (x, y, h + r * 0.6), (1.0, 1.0, rng.uniform(0.7, 1.5)), 12, name="crown")
    # Clutter near the camera and along the street: crates, bins, blocks, bollards.
    for i in range(clutter):
        x, y = rng.uniform(-6.0, 6.0), rng.uniform(1.5, depth * 0.6)
        if abs(x) < 1.2 and y < 6.0:
            x = math.copysign(1.2 + abs(x), x if x != 0 else 1.0)  # keep the camera's path clear
        kind = rng.random()
        material = rng.choice(walls + metals + ["accent0", "accent1"])
        if kind < 0.5:
            s = (rng.uniform(0.4, 2.5), rng.uniform(0.4, 2.5), rng.uniform(0.3, 2.0))
            b.box(material, s, (x, y, s[2] / 2), (0, 0, rng.uniform(0, math.pi)), name="crate")
        elif kind < 0.8:
            h = rng.uniform(0.5, 1.5)
            b.cylinder(material, rng.uniform(0.1, 0.6), h, (x, y, h / 2), segments=14, name="bin")
        else:
            r = rng.uniform(0.2, 0.9)
            b.sphere(material, r, (x, y, r), (1, 1, 1), 12, name="ball")
