"""Scene type "pool". An outdoor swimming pool: basin, loungers, umbrellas, fence, plants and a cabana.
The camera looks roughly along +y from near the origin; the scene extends in +y."""
import math


def build(b, p, rng):
    pool = p.vec("pool_size_m", [8.0, 16.0], 2, 2.0, 100.0)
    loungers = p.int("lounger_count", 10, 0, 200)
    umbrellas = p.int("umbrella_count", 5, 0, 100)
    plants = p.int("plant_count", 24, 0, 500)
    p.finish()
    pw, pl = pool
    y0 = 5.0
    deck_w, deck_l = pw + 16.0, pl + 16.0
    # Deck around the pool: four slabs leave the basin open.
    b.box("deck", (deck_w, y0 + 8, 0.2), (0, (y0 - 8) / 2, -0.1), name="deck")
    b.box("deck", (deck_w, 6.0, 0.2), (0, y0 + pl + 3.0, -0.1), name="deck")
    side_w = (deck_w - pw) / 2
    for s in (-1, 1):
        b.box("deck", (side_w, pl, 0.2), (s * (pw / 2 + side_w / 2), y0 + pl / 2, -0.1), name="deck")
    # Basin: tiled walls and floor, water surface slightly below the deck.
    b.box("pool_tiles", (pw, pl, 0.1), (0, y0 + pl / 2, -1.6), name="basin_floor")
    for s in (-1, 1):
        b.box("pool_tiles", (0.1, pl, 1.6), (s * pw / 2, y0 + pl / 2, -0.8), name="basin_wall")
        b.box("pool_tiles", (pw, 0.1, 1.6), (0, y0 + pl / 2 + s * pl / 2, -0.8), name="basin_wall")
    b.box("water", (pw, pl, 0.02), (0, y0 + pl / 2, -0.25), name="water")
    # Coping stones around the edge.
    for s in (-1, 1):
        b.box("coping", (0.4, pl + 0.8, 0.08), (s * (pw / 2 + 0.2), y0 + pl / 2, 0.04), name="coping")
        b.box("coping", (pw, 0.4, 0.08), (0, y0 + pl / 2 + s * (pl / 2 + 0.2), 0.04), name="coping")
    # Loungers on both sides.
    for i in range(loungers):
        s = -1 if i % 2 == 0 else 1
        y = y0 + 1.0 + (i // 2) * (pl - 2) / max(loungers // 2, 1)
        x = s * (pw / 2 + 2.2)
        mat = rng.choice(["lounger_white", "lounger_wood"])
        b.box(mat, (0.7, 1.4, 0.08), (x, y, 0.35), name="lounger_seat")
        b.box(mat, (0.7, 0.7, 0.08), (x, y + 0.95, 0.6), (math.radians(50), 0, 0), name="lounger_back")
        for dx in (-0.3, 0.3):
            for dy in (-0.6, 0.6):
                b.box("metal_frame", (0.04, 0.04, 0.33), (x + dx, y + dy, 0.16), name="lounger_leg")
        b.box("towel", (0.5, 0.9, 0.02), (x, y - 0.1, 0.4), (0, 0, rng.uniform(-0.2, 0.2)), name="towel")
    # Umbrellas: a pole and a cone canopy.
    for i in range(umbrellas):
        s = -1 if i % 2 == 0 else 1
        x = s * (pw / 2 + 3.6)
        y = y0 + 2.0 + i * (pl - 3) / max(umbrellas, 1)
        b.cylinder("metal_frame", 0.03, 2.4, (x, y, 1.2), segments=8, name="umbrella_pole")
        b.cylinder("umbrella", 1.3, 0.5, (x, y, 2.45), segments=12, radius2=0.02, name="umbrella")
    # Fence along the back and the sides, a cabana behind it.
    yb = y0 + pl + 5.0
    n_posts = 24
    for k in range(n_posts + 1):
        x = -deck_w / 2 + k * deck_w / n_posts
        b.box("fence", (0.08, 0.08, 1.4), (x, yb, 0.7), name="fence_post")
    for z in (0.5, 1.2):
        b.box("fence", (deck_w, 0.05, 0.08), (0, yb, z), name="fence_rail")
    for s in (-1, 1):
        for k in range(12):
            b.box("fence", (0.08, 0.08, 1.4), (s * deck_w / 2, y0 - 3 + k * (pl + 8) / 11, 0.7), name="fence_post")
        b.box("fence", (0.05, pl + 8, 0.08), (s * deck_w / 2, y0 + 1 + pl / 2, 1.2), name="fence_rail")
    cabana_x = rng.uniform(-3, 3)
    b.box("cabana", (9.0, 4.0, 3.2), (cabana_x, yb + 4.0, 1.6), name="cabana")
    b.box("roof", (10.0, 5.0, 0.3), (cabana_x, yb + 4.0, 3.35), name="cabana_roof")
    # Hedge behind the fence and potted plants on the deck.
    for k in range(14):
        b.sphere("foliage", rng.uniform(0.9, 1.4), (-deck_w / 2 + k * deck_w / 13, yb + 1.2, 0.8),
                 (1.2, 0.8, 0.9), 10, name="hedge")
    for i in range(plants):
        s = -1 if i % 2 == 0 else 1
        x = s * (pw / 2 + rng.uniform(5.0, 7.0))
        y = y0 - 2 + rng.uniform(0, pl + 4)
        b.cylinder("pot", 0.3, 0.5, (x, y, 0.25), segments=12, radius2=0.22, name="pot")
        for k in range(3):
            b.sphere("foliage", rng.uniform(0.3, 0.5), (x + rng.uniform(-0.2, 0.2), y + rng.uniform(-0.2, 0.2),
                                                      0.7 + k * 0.3), (1, 1, 1.2), 8, name="plant")
