"""Scene type "park" (a training scene of the restoration part, never a benchmark scene). A city park:
lawn, a gravel path, trees, benches, lamp posts, a round fountain and hedges.
The camera looks roughly along +y from near the origin; the scene extends in +y."""


def build(b, p, rng):
    size = p.vec("park_size_m", [30.0, 40.0], 2, 10.0, 200.0)
    trees = p.int("tree_count", 18, 0, 300)
    benches = p.int("bench_count", 6, 0, 100)
    lamps = p.int("lamp_count", 6, 0, 100)
    p.finish()
    w, l = size
    b.box("grass", (w, l, 0.2), (0, l / 2 - 4, -0.1), name="lawn")
    b.box("gravel", (3.0, l, 0.04), (0, l / 2 - 4, 0.02), name="path")
    # Fountain: basin ring, water, a column with a bowl.
    fy = l * 0.45
    b.cylinder("stone", 3.0, 0.6, (0, fy, 0.3), segments=32, name="fountain_basin")
    b.cylinder("water", 2.8, 0.05, (0, fy, 0.58), segments=32, name="fountain_water")
    b.cylinder("stone", 0.25, 1.6, (0, fy, 1.2), segments=16, name="fountain_column")
    b.cylinder("stone", 0.9, 0.25, (0, fy, 2.0), segments=24, radius2=0.4, name="fountain_bowl")
    for i in range(trees):
        side = -1 if i % 2 == 0 else 1
        x = side * rng.uniform(3.0, w / 2 - 1.5)
        y = rng.uniform(0.0, l - 6.0)
        h = rng.uniform(2.0, 3.5)
        b.cylinder("bark", rng.uniform(0.12, 0.22), h, (x, y, h / 2), segments=10, name="trunk")
        r = rng.uniform(1.2, 2.2)
        b.sphere("foliage", r, (x, y, h + r * 0.6), (1.0, 1.0, rng.uniform(0.8, 1.3)), 12, name="crown")
    for i in range(benches):
        side = -1 if i % 2 == 0 else 1
        y = 2.0 + (i // 2) * (l - 10) / max(benches // 2, 1)
        x = side * 2.1
        b.box("wood", (0.5, 1.8, 0.06), (x, y, 0.45), name="bench_seat")
        b.box("wood", (0.06, 1.8, 0.45), (x + side * 0.25, y, 0.75), name="bench_back")
        for dy in (-0.8, 0.8):
            b.box("iron", (0.5, 0.06, 0.45), (x, y + dy, 0.22), name="bench_leg")
    for i in range(lamps):
        side = 1 if i % 2 == 0 else -1
        y = 1.0 + i * (l - 8) / max(lamps, 1)
        x = side * 1.8
        b.cylinder("iron", 0.05, 3.6, (x, y, 1.8), segments=8, name="lamp_post")
        b.sphere("lamp_glass", 0.2, (x, y, 3.7), (1, 1, 1.2), 10, name="lamp")
    # Hedges along the back and the sides.
    for k in range(16):
        b.sphere("hedge", rng.uniform(0.9, 1.2), (-w / 2 + k * w / 15, l - 4.5, 0.6), (1.3, 0.8, 0.8), 10,
                 name="hedge")
    for s in (-1, 1):
        for k in range(12):
            b.sphere("hedge", rng.uniform(0.8, 1.1), (s * w / 2, k * (l - 4) / 11 - 3, 0.6), (0.8, 1.3, 0.8),
                     10, name="hedge")
    # A pavilion behind the hedge gives the far field structure.
    b.box("plaster", (8.0, 5.0, 3.5), (rng.uniform(-5, 5), l - 1.0, 1.75), name="pavilion")
    b.box("roof", (9.0, 6.0, 0.3), (0, l - 1.0, 3.65), name="pavilion_roof")
