"""Scene type "station" (a training scene of the restoration part, never a benchmark scene). A railway
platform: a canopy on columns, benches, signs and a kiosk beside two tracks with a standing train, a
footbridge and a station building at the far end. The camera stands on the platform and looks roughly
along +y; the tracks lie on the +x side."""


def build(b, p, rng):
    length = p.num("platform_length_m", 50.0, 15.0, 300.0)
    carriages = p.int("carriage_count", 3, 0, 20)
    benches = p.int("bench_count", 5, 0, 100)
    p.finish()
    b.box("ballast", (30.0, length + 30, 0.3), (6.0, length / 2, -1.15), name="track_bed")
    b.box("platform", (6.0, length + 10, 1.0), (-1.5, length / 2, -0.5), name="platform")
    b.box("platform_edge", (0.5, length + 10, 0.04), (1.25, length / 2, 0.02), name="platform_edge")
    for tx in (3.2, 7.6):  # two tracks: rails on sleepers
        for dx in (-0.72, 0.72):
            b.box("rail", (0.07, length + 30, 0.15), (tx + dx, length / 2, -0.92), name="rail")
        for k in range(int((length + 30) / 0.8)):
            b.box("sleeper", (2.4, 0.25, 0.12), (tx, k * 0.8 - 15, -1.0), name="sleeper")
    # Canopy: columns along the platform's middle and a slightly tilted roof.
    for k in range(int(length / 6)):
        b.cylinder("iron", 0.12, 3.6, (-1.5, 2.0 + k * 6.0, 1.8), segments=10, name="canopy_column")
    b.box("canopy_roof", (5.5, length * 0.8, 0.15), (-1.5, length * 0.42, 3.7), (0.06, 0, 0), name="canopy")
    for i in range(benches):
        y = 4.0 + i * (length * 0.7) / max(benches, 1) + rng.uniform(-1, 1)
        b.box("wood", (0.5, 2.0, 0.06), (-3.0, y, 0.45), name="bench_seat")
        b.box("wood", (0.06, 2.0, 0.45), (-3.25, y, 0.75), name="bench_back")
        for dy in (-0.9, 0.9):
            b.box("iron", (0.5, 0.06, 0.45), (-3.0, y + dy, 0.22), name="bench_leg")
    for k in range(3):  # hanging platform signs
        y = 8.0 + k * length * 0.25
        b.box("sign_blue", (0.06, 1.6, 0.45), (-1.5, y, 3.1), name="sign")
        b.box("iron", (0.03, 0.03, 0.5), (-1.5, y, 3.45), name="sign_hanger")
    b.box("kiosk", (2.2, 3.0, 2.6), (-3.2, length * 0.35, 1.3), name="kiosk")
    b.box("window", (0.05, 2.0, 1.0), (-2.08, length * 0.35, 1.6), name="kiosk_window")
    # A standing train on the far track: carriages with windows and a roof.
    y = 2.0
    for c in range(carriages):
        clen = rng.uniform(16.0, 20.0)
        colour = rng.choice(["train_red", "train_green"])
        b.box(colour, (2.8, clen, 3.0), (7.6, y + clen / 2, 0.9), name="carriage")
        b.cylinder("train_roof", 1.4, clen, (7.6, y + clen / 2, 2.4), (1.5708, 0, 0), segments=16,
                   name="carriage_roof")
        for w in range(int(clen / 2.2)):
            b.box("window", (0.05, 1.2, 0.8), (6.18, y + 1.4 + w * 2.2, 1.4), name="carriage_window")
        y += clen + 0.8
    # Overhead line masts beyond the tracks.
    for k in range(int(length / 10) + 1):
        b.cylinder("iron", 0.1, 6.5, (10.5, k * 10.0, 2.1), segments=8, name="mast")
        b.box("iron", (4.0, 0.08, 0.08), (8.6, k * 10.0, 5.2), name="mast_arm")
    # A footbridge across the tracks and a station building closing the view.
    fy = length * 0.7
    for x in (-3.5, 11.5):
        b.box("brick", (1.5, 2.5, 6.0), (x, fy, 2.0), name="bridge_tower")
    b.box("bridge", (16.5, 2.5, 0.6), (4.0, fy, 5.2), name="bridge_deck")
    b.box("bridge", (16.5, 0.1, 1.1), (4.0, fy - 1.2, 6.0), name="bridge_rail")
    b.box("brick", (24.0, 8.0, 9.0), (2.0, length + 8.0, 3.5), name="station_building")
    b.box("roof", (25.0, 9.0, 0.4), (2.0, length + 8.0, 8.2), name="station_roof")
    b.cylinder("clock", 0.9, 0.1, (2.0, length + 3.95, 6.5), (1.5708, 0, 0), segments=24, name="clock")
    b.box("hillside", (60.0, 10.0, 14.0), (30.0, length * 0.5, 4.0), (0, 0, 1.5708), name="embankment")
