"""Scene type "market" (a training scene of the restoration part, never a benchmark scene). A market
square: rows of stalls with striped canopies, crates of produce, barrels, a clock tower and houses.
The camera looks roughly along +y from near the origin; the scene extends in +y."""
import math


def build(b, p, rng):
    size = p.vec("square_size_m", [24.0, 36.0], 2, 10.0, 200.0)
    stalls = p.int("stalls_per_side", 6, 0, 50)
    barrels = p.int("barrel_count", 10, 0, 200)
    p.finish()
    w, l = size
    b.box("cobbles", (w + 10, l + 10, 0.2), (0, l / 2 - 2, -0.1), name="square")
    for side in (-1, 1):
        for i in range(stalls):
            y = 2.0 + i * (l - 8) / max(stalls, 1)
            x = side * 3.2
            b.box("wood", (1.6, 2.4, 0.08), (x, y, 0.9), name="stall_table")
            for dx in (-0.7, 0.7):
                for dy in (-1.1, 1.1):
                    b.box("wood", (0.08, 0.08, 2.4), (x + dx, y + dy, 1.2), name="stall_post")
            b.box(rng.choice(["canopy_red", "canopy_green", "canopy_yellow"]), (2.0, 2.8, 0.05),
                  (x, y, 2.45), (0, side * math.radians(12), 0), name="canopy")
            for k in range(rng.randint(2, 5)):
                cx, cy = x + rng.uniform(-0.5, 0.5), y + rng.uniform(-0.9, 0.9)
                b.box("crate", (0.5, 0.4, 0.25), (cx, cy, 1.07), name="crate")
                b.sphere(rng.choice(["produce_red", "produce_orange", "produce_green"]), 0.16,
                         (cx, cy, 1.25), (1.4, 1.1, 0.6), 8, name="produce")
    for i in range(barrels):
        x = (-1 if i % 2 == 0 else 1) * rng.uniform(5.0, w / 2 - 1.0)
        y = rng.uniform(0.0, l - 4)
        b.cylinder("barrel", 0.3, 0.9, (x, y, 0.45), segments=14, radius2=0.27, name="barrel")
    # Houses around the square and a clock tower at the far end.
    for side in (-1, 1):
        y = -2.0
        while y < l:
            d = rng.uniform(4.0, 7.0)
            h = rng.uniform(6.0, 11.0)
            b.box(rng.choice(["plaster", "plaster_ochre", "brick"]), (5.0, d - 0.2, h),
                  (side * (w / 2 + 2.5), y + d / 2, h / 2), name="house")
            b.box("roof", (5.6, d, 0.3), (side * (w / 2 + 2.5), y + d / 2, h + 0.15), name="house_roof")
            y += d
    b.box("brick", (4.0, 4.0, 16.0), (0, l + 3.0, 8.0), name="tower")
    b.cylinder("clock", 1.2, 0.1, (0, l + 0.95, 12.5), (math.pi / 2, 0, 0), segments=24, name="clock")
    b.box("houses_far", (w + 10, 4.0, 9.0), (0, l + 7.0, 4.5), name="far_row")
