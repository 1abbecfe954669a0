"""Scene type "factory". A factory yard: halls, containers, barrels, pipes and a gantry.
The camera looks roughly along +y from near the origin; the scene extends in +y."""
import math

from mathutils import Vector


def build(b, p, rng):
    yard = p.vec("yard_size_m", [30.0, 40.0], 2, 5.0, 300.0)
    containers = p.int("container_count", 10, 0, 200)
    barrels = p.int("barrel_count", 30, 0, 1000)
    tanks = p.int("tank_count", 3, 0, 50)
    pipes = p.int("pipe_count", 6, 0, 100)
    p.finish()
    W, L = yard
    b.box("concrete", (W + 10, L + 10, 0.2), (0, L / 2, -0.1), name="ground")
    # Brick hall at the back and a concrete wall on the left.
    b.box("brick", (W, 1.0, 9.0), (0, L, 4.5), name="hall")
    for k in range(6):
        b.box("window", (2.0, 0.1, 1.6), (-W / 2 + (k + 0.5) * W / 6, L - 0.52, 5.5), name="hall_window")
    b.box("door", (4.0, 0.1, 4.5), (rng.uniform(-4, 4), L - 0.52, 2.25), name="gate")
    b.box("concrete_wall", (0.6, L, 4.0), (-W / 2, L / 2, 2.0), name="wall")
    # Steel gantry: I-beams as three boxes each.
    def beam(p0, p1, size=0.3):
        d = Vector(p1) - Vector(p0)
        mid = (Vector(p0) + Vector(p1)) / 2
        rot = d.to_track_quat("Z", "Y").to_euler()
        b.box("steel", (size, size * 0.1, d.length), mid, rot, name="beam_web")
        b.box("steel", (size * 0.1, size, d.length), mid, rot, name="beam_flange")
    for k in range(4):
        y = 8.0 + k * 7.0
        for x in (-6.0, 6.0):
            beam((x, y, 0), (x, y, 7.0))
        beam((-6.0, y, 7.0), (6.0, y, 7.0))
    beam((-6.0, 8.0, 7.0), (-6.0, 29.0, 7.0))
    beam((6.0, 8.0, 7.0), (6.0, 29.0, 7.0))
    # Shipping containers, some stacked, on the right.
    for i in range(containers):
        stack = i % 3 == 2
        y = 6.0 + (i // 2) * 3.2 + rng.uniform(-0.3, 0.3)
        x = W / 2 - 4.0 - (i % 2) * 0.2
        z = 1.3 + (2.6 if stack else 0.0)
        b.box("container", (6.0, 2.4, 2.6), (x, y, z), (0, 0, math.radians(90 + rng.uniform(-4, 4))),
              name="container")
    # Tanks: cylinders with domed tops.
    for i in range(tanks):
        x = -W / 2 + 4.0 + i * 4.5
        y = L - 6.0 - rng.uniform(0, 3)
        h = rng.uniform(5.0, 8.0)
        r = rng.uniform(1.4, 2.0)
        b.cylinder("tank", r, h, (x, y, h / 2), segments=24, name="tank")
        b.sphere("tank", r, (x, y, h), (1.0, 1.0, 0.35), 24, name="tank_top")
    # Pipes on supports along the left wall.
    for i in range(pipes):
        z = 1.2 + i * 0.45
        r = rng.uniform(0.08, 0.2)
        b.cylinder(rng.choice(["pipe", "pipe_painted"]), r, L - 4, (-W / 2 + 1.0 + (i % 2) * 0.5, L / 2, z),
                   (math.pi / 2, 0, 0), segments=12, name="pipe")
    for k in range(6):
        b.box("steel", (1.4, 0.15, 0.15), (-W / 2 + 1.0, 3.0 + k * (L - 6) / 5, 1.0), name="pipe_support")
    # Barrels in clusters.
    for i in range(barrels):
        cx = rng.choice([-3.0, 2.0, -1.0]) + rng.uniform(-1.5, 1.5)
        cy = rng.choice([10.0, 15.0, 20.0]) + rng.uniform(-1.5, 1.5)
        b.cylinder("barrel", 0.3, 0.9, (cx, cy, 0.45), segments=16, name="barrel")
    # Pallets and crates for texture near the camera.
    for i in range(8):
        b.box("wood", (1.2, 1.0, 0.15 + 0.6 * rng.random()), (rng.uniform(-5, 5), rng.uniform(4, 12), 0.2),
              (0, 0, rng.uniform(0, math.pi)), name="pallet")
