"""Scene type "harbour" (a training scene of the restoration part, never a benchmark scene). A quay
beside open water: bollards, moored boats with cabins and masts, stacked containers and a crane.
The camera stands on the quay and looks roughly along +y; the water lies on the +x side."""


def build(b, p, rng):
    length = p.num("quay_length_m", 45.0, 10.0, 200.0)
    boats = p.int("boat_count", 6, 0, 50)
    containers = p.int("container_count", 12, 0, 100)
    p.finish()
    b.box("water", (60.0, length + 20, 0.05), (32.0, length / 2, -1.2), name="water")
    b.box("quay", (14.0, length + 20, 1.2), (-5.0, length / 2, -0.6), name="quay")
    b.box("quay_edge", (0.4, length + 20, 0.3), (1.8, length / 2, 0.15), name="quay_edge")
    for k in range(int(length / 4)):
        b.cylinder("bollard", 0.18, 0.6, (1.3, k * 4.0, 0.3), segments=12, name="bollard")
    for i in range(boats):
        y = 3.0 + i * (length - 6) / max(boats, 1) + rng.uniform(-1, 1)
        hull_l, hull_w = rng.uniform(6.0, 11.0), rng.uniform(2.2, 3.5)
        x = 2.5 + hull_w / 2 + rng.uniform(0.2, 0.8)
        b.box(rng.choice(["hull_white", "hull_blue", "hull_red"]), (hull_w, hull_l, 1.2), (x, y, -0.7),
              name="hull")
        b.box("deck_wood", (hull_w * 0.9, hull_l * 0.95, 0.06), (x, y, -0.08), name="boat_deck")
        b.box("cabin", (hull_w * 0.7, hull_l * 0.35, 1.4), (x, y - hull_l * 0.15, 0.65), name="cabin")
        if rng.random() < 0.6:
            h = rng.uniform(5.0, 9.0)
            b.cylinder("mast", 0.07, h, (x, y + hull_l * 0.15, h / 2), segments=8, name="mast")
    colours = ["container_red", "container_blue", "container_green"]
    for i in range(containers):
        stack = i % 3
        col = i // 3
        b.box(rng.choice(colours), (2.4, 6.0, 2.5), (-7.5 + (col % 2) * 2.6, 8.0 + (col // 2) * 6.5,
                                                     1.25 + stack * 2.55), name="container")
    # A portal crane over the quay and a warehouse behind.
    cy = length * 0.65
    for dx in (-6.0, 0.5):
        for dy in (-2.0, 2.0):
            b.box("crane", (0.5, 0.5, 14.0), (dx, cy + dy, 7.0), name="crane_leg")
    b.box("crane", (18.0, 1.0, 1.2), (2.0, cy, 14.5), name="crane_boom")
    b.box("warehouse", (8.0, length, 7.0), (-16.0, length / 2, 3.5), name="warehouse")
    b.box("roof", (9.0, length + 1, 0.4), (-16.0, length / 2, 7.2), name="warehouse_roof")
