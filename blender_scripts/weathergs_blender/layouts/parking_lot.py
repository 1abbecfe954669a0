"""Scene type "parking_lot" (a training scene of the restoration part, never a benchmark scene). An
open-air car park: asphalt with painted bays, rows of cars, light poles, kerbs and an office block.
The camera looks roughly along +y from near the origin; the scene extends in +y."""


def build(b, p, rng):
    size = p.vec("lot_size_m", [30.0, 45.0], 2, 10.0, 200.0)
    rows = p.int("row_count", 3, 1, 20)
    cars = p.int("cars_per_row", 8, 0, 50)
    poles = p.int("pole_count", 6, 0, 100)
    p.finish()
    w, l = size
    b.box("asphalt", (w, l, 0.2), (0, l / 2 - 4, -0.1), name="asphalt")
    bay = 2.6
    for r in range(rows):
        y = 4.0 + r * (l - 14) / max(rows, 1)
        for k in range(cars + 1):
            x = (k - cars / 2) * bay
            b.box("paint", (0.12, 5.0, 0.01), (x, y, 0.005), name="bay_line")
        b.box("kerb", (cars * bay + 2, 0.3, 0.15), (0, y + 3.0, 0.075), name="kerb")
        for k in range(cars):
            if rng.random() < 0.2:
                continue  # an empty bay
            x = (k - cars / 2 + 0.5) * bay + rng.uniform(-0.15, 0.15)
            paint = rng.choice(["car_red", "car_blue", "car_white", "car_grey"])
            length, width = rng.uniform(4.0, 4.7), rng.uniform(1.7, 1.9)
            b.box(paint, (width, length, 0.7), (x, y, 0.6), name="car_body")
            b.box("car_glass", (width * 0.9, length * 0.5, 0.5), (x, y - 0.2, 1.2), name="car_cabin")
            for dx in (-width / 2, width / 2):
                for dy in (-length * 0.33, length * 0.33):
                    b.cylinder("tyre", 0.32, 0.22, (x + dx, y + dy, 0.32), (0, 1.5708, 0), segments=12,
                               name="wheel")
    for i in range(poles):
        x = (-1 if i % 2 == 0 else 1) * (w / 2 - 2.0)
        y = 2.0 + (i // 2) * (l - 10) / max(poles // 2, 1)
        b.cylinder("steel", 0.08, 7.0, (x, y, 3.5), segments=8, name="light_pole")
        b.box("steel", (1.2, 0.3, 0.15), (x - 0.5 if x > 0 else x + 0.5, y, 7.0), name="light_head")
    # An office block at the far end with a row of windows.
    b.box("concrete", (w, 8.0, 10.0), (0, l + 1.0, 5.0), name="office")
    for k in range(10):
        for z in (2.0, 5.0, 8.0):
            b.box("window", (1.6, 0.05, 1.4), (-w / 2 + (k + 0.5) * w / 10, l - 3.05, z), name="window")
    for s in (-1, 1):
        for k in range(8):
            b.sphere("foliage", rng.uniform(0.8, 1.2), (s * (w / 2 + 0.5), k * (l - 4) / 7 - 3, 1.0),
                     (1, 1, 1.3), 10, name="shrub")
