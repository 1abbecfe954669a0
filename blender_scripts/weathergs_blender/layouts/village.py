"""Scene type "village" (a training scene of the restoration part, never a benchmark scene). A village
lane: cottages with pitched roofs and chimneys behind picket fences and front gardens, trees, a well,
parked carts and a church with a spire at the end of the lane. The camera looks roughly along +y from
near the origin; the scene extends in +y."""
import math


def build(b, p, rng):
    length = p.num("lane_length_m", 45.0, 10.0, 300.0)
    cottages = p.int("cottages_per_side", 5, 0, 60)
    trees = p.int("tree_count", 10, 0, 300)
    p.finish()
    b.box("meadow", (70.0, length + 40, 0.2), (0, length / 2, -0.1), name="ground")
    b.box("lane", (4.0, length + 10, 0.04), (0, length / 2, 0.02), name="lane")
    gap = length / max(cottages, 1)
    for side in (-1, 1):
        for i in range(cottages):
            y = (i + 0.5) * gap + rng.uniform(-1.0, 1.0)
            setback = rng.uniform(5.0, 8.0)
            w, d, h = rng.uniform(5.0, 7.0), min(gap - 1.0, rng.uniform(5.0, 8.0)), rng.uniform(2.6, 3.6)
            x = side * (2.0 + setback + w / 2)
            wall = rng.choice(["whitewash", "stone_wall", "timber"])
            b.box(wall, (w, d, h), (x, y, h / 2), name="cottage")
            roof = rng.choice(["thatch", "roof_tiles"])
            for s in (-1, 1):  # two roof planes at 35 degrees, ridge along y
                b.box(roof, (w * 0.62, d + 0.6, 0.15), (x + s * w * 0.25, y, h + w * 0.18),
                      (0, s * math.radians(35), 0), name="roof_plane")
            b.box("stone_wall", (0.6, 0.6, 1.6), (x + rng.uniform(-1.5, 1.5), y + d / 4, h + 1.6), name="chimney")
            b.box("door", (0.06, 0.9, 1.9), (x - side * (w / 2 + 0.03), y, 0.95), name="door")
            for dy in (-1.6, 1.6):
                b.box("window", (0.06, 0.8, 0.8), (x - side * (w / 2 + 0.03), y + dy, 1.5), name="window")
            # Picket fence along the lane with a gap for the garden path.
            fx = side * 2.6
            for k in range(int(gap / 0.25)):
                py = y - gap / 2 + k * 0.25
                if abs(py - y) < 0.6:
                    continue
                b.box("fence", (0.04, 0.08, 0.9), (fx, py, 0.45), name="picket")
            b.box("fence", (0.04, gap, 0.08), (fx, y, 0.7), name="fence_rail")
            b.box("gravel", (setback, 1.0, 0.03), (side * (2.6 + setback / 2), y, 0.03), name="garden_path")
            for k in range(rng.randint(2, 5)):
                b.sphere(rng.choice(["flowers_red", "flowers_blue", "hedge"]), rng.uniform(0.3, 0.6),
                         (side * rng.uniform(3.2, 2.2 + setback), y + rng.uniform(-gap / 2 + 0.8, gap / 2 - 0.8), 0.2),
                         (1.2, 1.2, 0.7), 10, name="shrub")
    for i in range(trees):
        side = -1 if i % 2 == 0 else 1
        x = side * rng.uniform(3.0, 22.0)
        y = rng.uniform(0.0, length)
        if abs(x) < 16.0:  # x is never on the lane (|x| >= 3): a draw among the cottages moves
            x = side * rng.uniform(16.0, 24.0)  # behind the cottages
        h = rng.uniform(2.5, 5.0)
        b.cylinder("bark", rng.uniform(0.15, 0.3), h, (x, y, h / 2), segments=10, name="trunk")
        r = rng.uniform(1.5, 3.0)
        b.sphere("foliage", r, (x, y, h + r * 0.6), (1.0, 1.0, rng.uniform(0.9, 1.4)), 12, name="crown")
    # A well beside the lane and a cart.
    wy = length * 0.3
    b.cylinder("stone_wall", 0.9, 0.9, (-3.4, wy, 0.45), segments=20, name="well")
    for dy in (-0.7, 0.7):
        b.box("timber", (0.12, 0.12, 2.0), (-3.4, wy + dy, 1.0), name="well_post")
    b.box("roof_tiles", (1.4, 1.9, 0.1), (-3.4, wy, 2.05), name="well_roof")
    cy = length * 0.55
    b.box("timber", (1.3, 2.4, 0.5), (2.0, cy, 0.8), name="cart")
    for dy in (-0.7, 0.7):
        b.cylinder("timber", 0.5, 0.1, (2.7, cy + dy, 0.5), (0, math.pi / 2, 0), segments=16, name="cart_wheel")
    # The church at the end of the lane: nave, tower and spire.
    b.box("stone_wall", (9.0, 16.0, 7.0), (0, length + 10.0, 3.5), name="nave")
    for s in (-1, 1):
        b.box("roof_tiles", (5.8, 16.6, 0.2), (s * 2.3, length + 10.0, 8.6), (0, s * math.radians(40), 0),
              name="nave_roof")
    b.box("stone_wall", (4.0, 4.0, 14.0), (0, length + 1.0, 7.0), name="tower")
    b.cylinder("roof_tiles", 2.6, 7.0, (0, length + 1.0, 17.5), segments=4, radius2=0.05, name="spire")
    b.cylinder("clock", 0.8, 0.1, (0, length - 1.05, 11.0), (math.pi / 2, 0, 0), segments=24, name="clock")
