"""Scene type "tanabata". A Tanabata festival street: shops on both sides, bamboo poles with paper streamers, lanterns.
The camera looks roughly along +y from near the origin; the scene extends in +y."""
import math


def build(b, p, rng):
    street_w = p.num("street_width_m", 8.0, 3.0, 30.0)
    length = p.num("street_length_m", 40.0, 10.0, 200.0)
    poles = p.int("bamboo_count", 10, 0, 200)
    streamers = p.int("streamers_per_bamboo", 14, 0, 100)
    shops = p.int("shops_per_side", 7, 0, 100)
    lanterns = p.int("lantern_count", 24, 0, 500)
    p.finish()
    b.box("paving", (street_w + 12, length + 20, 0.2), (0, length / 2, -0.1), name="ground")
    # Shop fronts on both sides: walls, awnings, signs, windows.
    shop_w = length / max(shops, 1)
    for side in (-1, 1):
        x_front = side * street_w / 2
        for i in range(shops):
            y = (i + 0.5) * shop_w
            h = rng.uniform(3.5, 6.5)
            d = rng.uniform(3.0, 5.0)
            b.box(rng.choice(["shop_wall", "shop_wood", "shop_brick"]), (d, shop_w - 0.2, h),
                  (x_front + side * (d / 2 + 0.3), y, h / 2), name="shop")
            b.box("awning", (1.4, shop_w - 0.4, 0.06), (x_front + side * 0.2, y, 2.7),
                  (0, -side * math.radians(18), 0), name="awning")
            b.box("sign", (0.08, shop_w * rng.uniform(0.4, 0.7), rng.uniform(0.5, 0.9)),
                  (x_front + side * 0.26, y, rng.uniform(3.2, 3.8)), name="sign")
            b.box("window", (0.05, shop_w * 0.5, 1.4), (x_front + side * 0.27, y + rng.uniform(-0.3, 0.3), 1.3),
                  name="window")
            # Goods stands in front of the shops.
            if rng.random() < 0.7:
                b.box("crate", (0.7, rng.uniform(0.8, 1.6), 0.8), (x_front - side * 0.4, y, 0.4), name="stand")
    # Bamboo poles with long paper streamers along both kerbs.
    for i in range(poles):
        side = -1 if i % 2 == 0 else 1
        x = side * (street_w / 2 - 0.9) + rng.uniform(-0.2, 0.2)
        y = 2.0 + (i / max(poles - 1, 1)) * (length - 6) + rng.uniform(-0.8, 0.8)
        h = rng.uniform(6.0, 8.0)
        b.cylinder("bamboo", 0.06, h, (x, y, h / 2), segments=10, name="bamboo")
        for k in range(5):
            b.sphere("leaves", rng.uniform(0.5, 0.8), (x + rng.uniform(-0.6, 0.6), y + rng.uniform(-0.6, 0.6),
                                                     h - rng.uniform(0.0, 1.2)), (1.0, 1.0, 0.5), 8, name="leaves")
        ring_z = h - 1.6
        b.cylinder("paper", 0.45, 0.25, (x, y, ring_z), segments=16, name="ball")
        for s in range(streamers):
            a = 2 * math.pi * s / max(streamers, 1) + rng.uniform(-0.1, 0.1)
            L = rng.uniform(1.6, 3.2)
            r = 0.42
            b.box("streamer", (0.09, 0.006, L), (x + r * math.cos(a), y + r * math.sin(a), ring_z - L / 2),
                  (rng.uniform(-0.08, 0.08), rng.uniform(-0.08, 0.08), a + math.pi / 2), name="streamer")
    # Lanterns on wires across the street.
    rows = max(1, lanterns // 6)
    for r in range(rows):
        y = 4.0 + r * (length - 8) / max(rows, 1)
        z = 4.3 + rng.uniform(-0.2, 0.2)
        b.cylinder("wire", 0.01, street_w, (0, y, z + 0.35), (0, math.pi / 2, 0), segments=6, name="wire")
        per_row = lanterns // rows
        for k in range(per_row):
            x = -street_w / 2 + (k + 0.5) * street_w / per_row
            b.sphere(rng.choice(["lantern_red", "lantern_white"]), 0.22, (x, y, z), (1.0, 1.0, 1.35), 12,
                     name="lantern")
