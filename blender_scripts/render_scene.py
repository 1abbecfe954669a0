# Renders one weathergs scene variant headless in Blender 3.4 (EEVEE or Cycles).
#
#   blender -b --factory-startup --python-exit-code 1 --python render_scene.py -- JOB.json
#
# Talks to C++ only through files (docs/scenes.md, "Blender job files"):
#   in : JOB.json  {"scene": {...}, "scene_file": "...", "surface": {...}, "lights": {...},
#                   "render": {...}, "camera": {... "clip_start_m", "clip_end_m"}, "markers": [...],
#                   "outputs": {"images": IMG, "depth": DEPTH}, "output_dir": "..."}
#   out: <output_dir>/IMG/<view>.png         8-bit sRGB (view transform "Standard")
#        <output_dir>/DEPTH/<view>.exr       planar camera z, float32, R=G=B, background 65504 (EEVEE)
# Folder names and the clip range come from the job: datagen/blender.cc owns them.
#        <output_dir>/cameras.json           DATASET_FORMAT.md cameras, recomputed from Blender's camera
#        <output_dir>/render_log.json        timings and object counts
#        <output_dir>/error.json             only on failure: {"where": "...", "what": "..."}
# The layout and material parameters of the scene spec are validated here (unknown keys are errors);
# everything else was validated by the C++ side before the job was written.
import json
import math
import os
import random
import sys
import time
import traceback

import bmesh
import bpy
from mathutils import Matrix, Vector


class SpecError(Exception):
    def __init__(self, where, what):
        super().__init__(f"{where}: {what}")
        self.where = where
        self.what = what


def _type_name(v):
    if isinstance(v, bool):
        return "a boolean"
    if isinstance(v, (int, float)):
        return "a number"
    if isinstance(v, str):
        return "a string"
    if isinstance(v, list):
        return "an array"
    if isinstance(v, dict):
        return "an object"
    return "null"


class Params:
    """Strict reader of one JSON object: typed getters with defaults, unknown keys are errors."""

    def __init__(self, data, where):
        if not isinstance(data, dict):
            raise SpecError(where, "expected an object, got " + _type_name(data))
        self.data = data
        self.where = where
        self.used = set()

    def _at(self, key):
        return f"{self.where}/{key}"

    def has(self, key):
        return key in self.data

    def num(self, key, default, lo=None, hi=None):
        self.used.add(key)
        v = self.data.get(key, default)
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise SpecError(self._at(key), "expected a number, got " + _type_name(v))
        if (lo is not None and v < lo) or (hi is not None and v > hi):
            raise SpecError(self._at(key), f"expected a number in [{lo}, {hi}], got {v}")
        return float(v)

    def int(self, key, default, lo=0, hi=100000):
        self.used.add(key)
        v = self.data.get(key, default)
        if isinstance(v, bool) or not isinstance(v, int):
            raise SpecError(self._at(key), "expected an integer, got " + _type_name(v))
        if v < lo or v > hi:
            raise SpecError(self._at(key), f"expected an integer in [{lo}, {hi}], got {v}")
        return v

    def vec(self, key, default, n=3, lo=None, hi=None):
        self.used.add(key)
        v = self.data.get(key, default)
        if not isinstance(v, list) or len(v) != n or any(
                isinstance(x, bool) or not isinstance(x, (int, float)) for x in v):
            raise SpecError(self._at(key), f"expected an array of {n} numbers")
        if any((lo is not None and x < lo) or (hi is not None and x > hi) for x in v):
            raise SpecError(self._at(key), f"expected values in [{lo}, {hi}]")
        return [float(x) for x in v]

    def str(self, key, default, choices=None):
        self.used.add(key)
        v = self.data.get(key, default)
        if not isinstance(v, str):
            raise SpecError(self._at(key), "expected a string, got " + _type_name(v))
        if choices is not None and v not in choices:
            raise SpecError(self._at(key), f"expected one of {sorted(choices)}, got \"{v}\"")
        return v

    def child(self, key):
        self.used.add(key)
        if key not in self.data:
            raise SpecError(self._at(key), "missing required object")
        return Params(self.data[key], self._at(key))

    def finish(self):
        unknown = sorted(set(self.data) - self.used)
        if unknown:
            raise SpecError(self._at(unknown[0]), "unknown key (misspelled?)")


# ---------------------------------------------------------------------------------------------------
# Materials. Every material is data: a pattern plus colors and scales from the scene spec. Textures use
# object coordinates (meshes carry their real size, so 1 unit = 1 m) offset by the object's random
# number, so identical props never repeat the same texture (repeats cause false SfM matches).
# Bump inputs are always one small separate texture node: EEVEE re-evaluates a Bump node's whole input
# graph for its derivatives, and large graphs made Mesa's shader compile take minutes (ENVIRONMENT.md).

PATTERNS = {"noise", "brick", "tiles", "voronoi", "wave", "emissive", "water", "metal", "foliage"}


class NodeGraph:
    def __init__(self, mat):
        mat.use_nodes = True
        self.nt = mat.node_tree
        self.nt.nodes.clear()

    def node(self, kind, **inputs):
        n = self.nt.nodes.new(kind)
        for k, v in inputs.items():
            self.set(n.inputs[k], v)
        return n

    def set(self, socket, v):
        if hasattr(v, "is_output") or isinstance(v, bpy.types.NodeSocket):
            self.nt.links.new(v, socket)
        elif isinstance(v, (list, tuple)) and len(v) == 3 and socket.type == "RGBA":
            socket.default_value = (v[0], v[1], v[2], 1.0)
        else:
            socket.default_value = v

    def math(self, op, a, b=0.0, clamp=False):
        n = self.nt.nodes.new("ShaderNodeMath")
        n.operation = op
        n.use_clamp = clamp
        self.set(n.inputs[0], a)
        self.set(n.inputs[1], b)
        return n.outputs[0]

    def mix(self, fac, a, b, blend="MIX"):
        n = self.nt.nodes.new("ShaderNodeMixRGB")
        n.blend_type = blend
        self.set(n.inputs["Fac"], fac)
        self.set(n.inputs["Color1"], a)
        self.set(n.inputs["Color2"], b)
        return n.outputs["Color"]

    def smoothstep(self, x, lo, hi):
        n = self.nt.nodes.new("ShaderNodeMapRange")
        n.interpolation_type = "SMOOTHSTEP"
        self.set(n.inputs[0], x)
        n.inputs[1].default_value = lo
        n.inputs[2].default_value = hi
        n.inputs[3].default_value = 0.0
        n.inputs[4].default_value = 1.0
        return n.outputs[0]


def texture_vector(g, axes):
    """Object coordinates (meters) offset per object; axes picks the 2D plane of planar patterns."""
    coords = g.node("ShaderNodeTexCoord")
    info = g.node("ShaderNodeObjectInfo")
    offset = g.node("ShaderNodeVectorMath")
    offset.operation = "MULTIPLY"
    g.set(offset.inputs[0], info.outputs["Random"])
    offset.inputs[1].default_value = (173.0, 291.0, 57.0)
    add = g.node("ShaderNodeVectorMath")
    add.operation = "ADD"
    g.set(add.inputs[0], coords.outputs["Object"])
    g.set(add.inputs[1], offset.outputs[0])
    vec = add.outputs[0]
    if axes != "xy":
        sep = g.node("ShaderNodeSeparateXYZ", Vector=vec)
        comb = g.node("ShaderNodeCombineXYZ")
        a, b = axes[0].upper(), axes[1].upper()
        third = ({"X", "Y", "Z"} - {a, b}).pop()
        g.set(comb.inputs["X"], sep.outputs[a])
        g.set(comb.inputs["Y"], sep.outputs[b])
        g.set(comb.inputs["Z"], sep.outputs[third])
        vec = comb.outputs[0]
    return vec, info.outputs["Random"]


def build_material(name, p, surface):
    """p: Params of scenes/<scene>.json:/materials/<name>. surface: the variant's surface state."""
    pattern = p.str("pattern", "noise", PATTERNS)
    color = p.vec("color", [0.5, 0.5, 0.5], 3, 0.0, 1.0)
    color2 = p.vec("color2", color, 3, 0.0, 1.0)
    scale_m = p.num("scale_m", 0.5, 1e-3, 100.0)
    roughness = p.num("roughness", 0.6, 0.0, 1.0)
    metallic = p.num("metallic", 1.0 if pattern == "metal" else 0.0, 0.0, 1.0)
    hue_var = p.num("hue_variation", 0.0, 0.0, 1.0)
    value_var = p.num("value_variation", 0.15, 0.0, 1.0)
    bump = p.num("bump", 0.3, 0.0, 1.0)
    axes = p.str("axes", "xy", {"xy", "xz", "yz"})
    emission = p.num("emission_strength", 0.0, 0.0, 100.0)
    porosity = p.num("porosity", 0.5, 0.0, 1.0)  # how much rain darkens it (paper, brick > metal)
    mortar = p.vec("mortar_color", [0.55, 0.53, 0.5], 3, 0.0, 1.0) if pattern in ("brick", "tiles") else None
    brick_ratio = p.num("brick_ratio", 2.0, 0.2, 10.0) if pattern == "brick" else 1.0
    p.finish()

    mat = bpy.data.materials.new(name)
    g = NodeGraph(mat)
    vec, rnd = texture_vector(g, axes)
    freq = 1.0 / scale_m
    detail_noise = g.node("ShaderNodeTexNoise", Vector=vec, Scale=freq * 4.0, Detail=6.0, Roughness=0.55)
    base = None
    height = None  # the small separate graph feeding the Bump node
    if pattern in ("noise", "metal", "foliage"):
        n = g.node("ShaderNodeTexNoise", Vector=vec, Scale=freq, Detail=8.0, Roughness=0.6)
        base = g.mix(g.smoothstep(n.outputs["Fac"], 0.35, 0.65), color, color2)
        if pattern == "foliage":
            v = g.node("ShaderNodeTexVoronoi", Vector=vec, Scale=freq * 3.0)
            base = g.mix(g.math("MULTIPLY", v.outputs["Distance"], 1.5, clamp=True), base, color2)
        height = g.node("ShaderNodeTexNoise", Vector=vec, Scale=freq * 2.0, Detail=3.0).outputs["Fac"]
    elif pattern == "voronoi":
        v = g.node("ShaderNodeTexVoronoi", Vector=vec, Scale=freq)
        base = g.mix(g.math("MULTIPLY", v.outputs["Color"], 1.0), color, color2)
        base = g.mix(g.smoothstep(v.outputs["Distance"], 0.2, 0.6), base, color2)
        height = g.node("ShaderNodeTexVoronoi", Vector=vec, Scale=freq).outputs["Distance"]
    elif pattern in ("brick", "tiles"):
        bw = scale_m
        bh = scale_m / brick_ratio
        b = g.node("ShaderNodeTexBrick", Vector=vec, Color1=color, Color2=color2, Mortar=mortar, Scale=1.0,
                   **{"Mortar Size": 0.06 * bh, "Brick Width": bw, "Row Height": bh, "Bias": 0.0})
        b.offset = 0.5 if pattern == "brick" else 0.0
        base = b.outputs["Color"]
        hb = g.node("ShaderNodeTexBrick", Vector=vec, Scale=1.0,
                    **{"Mortar Size": 0.06 * bh, "Brick Width": bw, "Row Height": bh})
        hb.offset = b.offset
        height = g.math("SUBTRACT", 1.0, hb.outputs["Fac"])
    elif pattern == "wave":
        w = g.node("ShaderNodeTexWave", Vector=vec, Scale=freq, Distortion=2.0, Detail=3.0)
        w.bands_direction = "Z" if axes == "xy" else "X"
        base = g.mix(w.outputs["Fac"], color, color2)
        hw = g.node("ShaderNodeTexWave", Vector=vec, Scale=freq)
        hw.bands_direction = w.bands_direction
        height = hw.outputs["Fac"]
    elif pattern == "emissive":
        n = g.node("ShaderNodeTexNoise", Vector=vec, Scale=freq, Detail=4.0)
        base = g.mix(n.outputs["Fac"], color, color2)
        height = None
    elif pattern == "water":
        n = g.node("ShaderNodeTexNoise", Vector=vec, Scale=freq * 0.5, Detail=3.0)
        base = g.mix(n.outputs["Fac"], color, color2)
        hw = g.node("ShaderNodeTexWave", Vector=vec, Scale=freq, Distortion=6.0, Detail=2.0)
        hw.wave_type = "RINGS"
        height = hw.outputs["Fac"]

    # Dirt / grain on every material so that large uniform areas still have features for SfM.
    base = g.mix(g.math("MULTIPLY", detail_noise.outputs["Fac"], value_var * 2.0), base, [0.05, 0.05, 0.05])
    if hue_var > 0 or value_var > 0:
        hs = g.node("ShaderNodeHueSaturation", Color=base)
        g.set(hs.inputs["Hue"], g.math("ADD", g.math("MULTIPLY", g.math("SUBTRACT", rnd, 0.5), hue_var), 0.5))
        g.set(hs.inputs["Value"], g.math("ADD", g.math("MULTIPLY", rnd, value_var), 1.0 - value_var * 0.5))
        base = hs.outputs["Color"]

    rough = roughness
    if pattern == "metal":
        rough = g.math("ADD", g.math("MULTIPLY", detail_noise.outputs["Fac"], 0.4), roughness * 0.8, clamp=True)

    normal = None
    if height is not None and bump > 0:
        bn = g.node("ShaderNodeBump", Strength=bump, Distance=0.02, Height=height)
        normal = bn.outputs["Normal"]

    base, rough, normal = apply_surface_state(g, vec, base, rough, normal, surface, porosity,
                                              pattern in ("emissive", "water"))

    bsdf = g.node("ShaderNodeBsdfPrincipled", **{"Base Color": base, "Roughness": rough, "Metallic": metallic})
    if pattern == "water":
        bsdf.inputs["Specular"].default_value = 0.8
    if normal is not None:
        g.set(bsdf.inputs["Normal"], normal)
    if pattern == "emissive" and emission > 0:
        g.set(bsdf.inputs["Emission"], base)
        bsdf.inputs["Emission Strength"].default_value = emission
    out = g.node("ShaderNodeOutputMaterial")
    g.set(out.inputs["Surface"], bsdf.outputs["BSDF"])
    return mat


def apply_surface_state(g, vec, base, rough, normal, surface, porosity, exempt):
    """Snow cover on upward surfaces (normal and noise driven) or wet, darker, glossier surfaces with
    puddles. Returns the modified (base color, roughness, normal) sockets/values."""
    kind = surface.get("kind", "clear")
    if kind == "clear" or exempt:
        return base, rough, normal
    geo = g.node("ShaderNodeNewGeometry")
    nz = g.node("ShaderNodeSeparateXYZ", Vector=geo.outputs["Normal"]).outputs["Z"]
    if kind == "snow":
        coverage = surface["coverage"]
        noise = g.node("ShaderNodeTexNoise", Vector=vec, Scale=1.0 / surface["noise_scale_m"], Detail=5.0)
        upward = g.smoothstep(nz, surface["normal_threshold"], surface["normal_threshold"] + 0.25)
        # Noise in [0.3, 0.7] mostly; coverage shifts the threshold so 0 means none and 1 means all.
        patch = g.smoothstep(g.math("ADD", noise.outputs["Fac"], coverage - 0.5), 0.4, 0.6)
        f = g.math("MULTIPLY", upward, patch, clamp=True)
        # Snow is not a flat white: fine grain and drifts keep features for SfM and avoid clipping.
        grain = g.node("ShaderNodeTexNoise", Vector=vec, Scale=12.0 / surface["noise_scale_m"], Detail=4.0)
        shade = g.math("ADD", g.math("MULTIPLY", grain.outputs["Fac"], 0.35), 0.65)
        snow = g.mix(1.0, surface["color"], g.node("ShaderNodeCombineXYZ", X=shade, Y=shade, Z=shade).outputs[0],
                     blend="MULTIPLY")
        base = g.mix(f, base, snow)
        rough = g.math("ADD", g.math("MULTIPLY", f, 0.75), g.math("MULTIPLY", g.math("SUBTRACT", 1.0, f), rough))
        if normal is not None:
            flat = g.node("ShaderNodeNewGeometry").outputs["Normal"]
            mixn = g.node("ShaderNodeMixRGB", Fac=f, Color1=normal, Color2=flat)
            normal = mixn.outputs["Color"]
        return base, rough, normal
    # rain
    wet = surface["wetness"]
    dark = 1.0 - surface["darkening"] * (0.4 + 0.6 * porosity) * wet
    base = g.mix(1.0, base, [dark, dark, dark], blend="MULTIPLY")
    glossy = max(0.05, 1.0 - 0.85 * wet)
    rough = g.math("MULTIPLY", rough, glossy) if not isinstance(rough, float) else rough * glossy
    noise = g.node("ShaderNodeTexNoise", Vector=vec, Scale=1.0 / surface["puddle_scale_m"], Detail=2.0)
    upward = g.smoothstep(nz, 0.9, 0.97)
    patch = g.smoothstep(g.math("ADD", noise.outputs["Fac"], surface["puddle_coverage"] - 0.5), 0.47, 0.53)
    f = g.math("MULTIPLY", upward, patch, clamp=True)
    base = g.mix(f, base, g.mix(1.0, base, [0.35, 0.35, 0.38], blend="MULTIPLY"))
    rough = g.math("ADD", g.math("MULTIPLY", f, 0.02), g.math("MULTIPLY", g.math("SUBTRACT", 1.0, f), rough))
    if normal is not None:
        flat = g.node("ShaderNodeNewGeometry").outputs["Normal"]
        normal = g.node("ShaderNodeMixRGB", Fac=f, Color1=normal, Color2=flat).outputs["Color"]
    return base, rough, normal


# ---------------------------------------------------------------------------------------------------
# Geometry: every object gets its own small mesh with its real dimensions (object coordinates are
# meters), built with bmesh, which is far faster than bpy.ops for hundreds of objects.

class Builder:
    def __init__(self, materials, collection):
        self.materials = materials
        self.collection = collection
        self.count = 0

    def _object(self, name, bm, material, location, rotation, smooth):
        mesh = bpy.data.meshes.new(name)
        if smooth:
            for f in bm.faces:
                f.smooth = abs(f.normal.z) < 0.99 if smooth == "sides" else True
        bm.to_mesh(mesh)
        bm.free()
        if material not in self.materials:
            raise SpecError("materials", f"the layout uses material \"{material}\", which the spec lacks")
        mesh.materials.append(self.materials[material])
        obj = bpy.data.objects.new(name, mesh)
        obj.location = location
        obj.rotation_euler = rotation
        self.collection.objects.link(obj)
        self.count += 1
        return obj

    def box(self, material, size, location, rotation=(0, 0, 0), name="box"):
        bm = bmesh.new()
        bmesh.ops.create_cube(bm, size=1.0)
        bmesh.ops.scale(bm, vec=Vector(size), verts=bm.verts)
        return self._object(name, bm, material, location, rotation, False)

    def cylinder(self, material, radius, depth, location, rotation=(0, 0, 0), segments=16, radius2=None,
                 name="cylinder"):
        bm = bmesh.new()
        bmesh.ops.create_cone(bm, cap_ends=True, cap_tris=False, segments=segments, radius1=radius,
                              radius2=radius if radius2 is None else radius2, depth=depth)
        return self._object(name, bm, material, location, rotation, "sides")

    def sphere(self, material, radius, location, scale=(1, 1, 1), segments=16, name="sphere"):
        bm = bmesh.new()
        bmesh.ops.create_uvsphere(bm, u_segments=segments, v_segments=max(6, segments // 2), radius=radius)
        bmesh.ops.scale(bm, vec=Vector(scale), verts=bm.verts)
        return self._object(name, bm, material, location, (0, 0, 0), True)


# ---------------------------------------------------------------------------------------------------
# Scene layouts. The camera looks roughly along +y from near the origin; scenes extend in +y.

def build_tanabata(b, p, rng):
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


def build_factory(b, p, rng):
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


def build_pool(b, p, rng):
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


LAYOUTS = {"tanabata": build_tanabata, "factory": build_factory, "pool": build_pool}


# ---------------------------------------------------------------------------------------------------

def setup_lights(lights):
    world = bpy.data.worlds.new("sky")
    bpy.context.scene.world = world
    world.use_nodes = True
    nt = world.node_tree
    bg = nt.nodes["Background"]
    sky = lights["sky"]
    # Vertical gradient: horizon to zenith, so reflections and the sky region have some structure.
    coords = nt.nodes.new("ShaderNodeTexCoord")
    sep = nt.nodes.new("ShaderNodeSeparateXYZ")
    nt.links.new(coords.outputs["Generated"], sep.inputs[0])
    ramp = nt.nodes.new("ShaderNodeValToRGB")
    nt.links.new(sep.outputs["Z"], ramp.inputs[0])
    ramp.color_ramp.elements[0].position = 0.5
    ramp.color_ramp.elements[0].color = (*sky["horizon_color"], 1.0)
    ramp.color_ramp.elements[1].position = 1.0
    ramp.color_ramp.elements[1].color = (*sky["zenith_color"], 1.0)
    nt.links.new(ramp.outputs["Color"], bg.inputs["Color"])
    bg.inputs["Strength"].default_value = sky["strength"]
    sun = lights["sun"]
    if sun["strength"] > 0:
        data = bpy.data.lights.new("sun", "SUN")
        data.energy = sun["strength"]
        data.color = sun["color"]
        data.angle = math.radians(sun["angle_deg"])
        obj = bpy.data.objects.new("sun", data)
        el, az = math.radians(sun["elevation_deg"]), math.radians(sun["azimuth_deg"])
        to_sun = Vector((math.cos(el) * math.sin(az), math.cos(el) * math.cos(az), math.sin(el)))
        obj.rotation_euler = to_sun.to_track_quat("Z", "Y").to_euler()
        bpy.context.scene.collection.objects.link(obj)


def blender_from_opencv(camera_from_world):
    """world_from_camera in Blender camera axes (x right, y up, -z forward) from our OpenCV pose."""
    m = Matrix(camera_from_world)
    r_cv = m.to_3x3()
    t = m.col[3].to_3d()
    flip = Matrix(((1, 0, 0), (0, -1, 0), (0, 0, -1)))
    r_bw = r_cv.transposed() @ flip
    center = -(r_cv.transposed() @ t)
    out = r_bw.to_4x4()
    out.translation = center
    return out


def opencv_from_blender(cam_obj):
    mw = cam_obj.matrix_world
    r_bw = mw.to_3x3().normalized()
    flip = Matrix(((1, 0, 0), (0, -1, 0), (0, 0, -1)))
    r_cv = flip @ r_bw.transposed()
    t = -(r_cv @ mw.translation)
    return [[r_cv[i][0], r_cv[i][1], r_cv[i][2], t[i]] for i in range(3)] + [[0.0, 0.0, 0.0, 1.0]]


def intrinsics(cam_data, width, height):
    # Sensor fit horizontal (width >= height, checked by the C++ side); pixel-corner origin.
    f = cam_data.lens / cam_data.sensor_width * width
    s = max(width, height)
    return f, f, width / 2 - cam_data.shift_x * s, height / 2 + cam_data.shift_y * s


def setup_render(render, out_dir, depth_dir):
    scene = bpy.context.scene
    scene.render.resolution_x = render["width"]
    scene.render.resolution_y = render["height"]
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.image_settings.color_depth = "8"
    scene.render.dither_intensity = 0.0  # dithering is noise: keep renders of one view identical
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = render.get("exposure_ev", 0.0)
    if render["engine"] == "eevee":
        scene.render.engine = "BLENDER_EEVEE"
        ee = scene.eevee
        ee.taa_render_samples = render["samples"]
        ee.use_gtao = True
        ee.gtao_distance = 1.0
        ee.use_ssr = True
        ee.use_soft_shadows = True
        ee.shadow_cascade_size = "1024"
        ee.use_bloom = False
    else:
        scene.render.engine = "CYCLES"
        scene.cycles.device = "CPU"
        scene.cycles.samples = render["samples"]
        scene.cycles.use_denoising = False  # this build has no OpenImageDenoise (ENVIRONMENT.md)
        scene.cycles.seed = render["seed"]
        scene.cycles.use_adaptive_sampling = False
    # Depth through the compositor: File Output node, float32 EXR (R=G=B = planar camera z).
    bpy.context.view_layer.use_pass_z = True
    scene.use_nodes = True
    nt = scene.node_tree
    nt.nodes.clear()
    rl = nt.nodes.new("CompositorNodeRLayers")
    comp = nt.nodes.new("CompositorNodeComposite")
    nt.links.new(rl.outputs["Image"], comp.inputs["Image"])
    fo = nt.nodes.new("CompositorNodeOutputFile")
    fo.base_path = os.path.join(out_dir, depth_dir)
    fo.format.file_format = "OPEN_EXR"
    fo.format.color_depth = "32"
    fo.format.color_mode = "RGB"
    fo.format.exr_codec = "ZIP"
    nt.links.new(rl.outputs["Depth"], fo.inputs[0])
    return fo


def add_markers(markers):
    if not markers:
        return 0
    mat = bpy.data.materials.new("marker")
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (1.0, 0.0, 1.0, 1.0)
    em.inputs["Strength"].default_value = 1.0
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(em.outputs[0], out.inputs["Surface"])
    for i, m in enumerate(markers):
        bm = bmesh.new()
        bmesh.ops.create_uvsphere(bm, u_segments=32, v_segments=16, radius=m["radius_m"])
        mesh = bpy.data.meshes.new(f"marker{i}")
        for f in bm.faces:
            f.smooth = True
        bm.to_mesh(mesh)
        bm.free()
        mesh.materials.append(mat)
        obj = bpy.data.objects.new(f"marker{i}", mesh)
        obj.location = m["p_world"]
        bpy.context.scene.collection.objects.link(obj)
    return len(markers)


def add_particles(particles):
    """Airborne particles for the path-tracer validation only (docs/scenes.md): rain drops as water
    spheres (glass, IOR 1.333), snow flakes as translucent white spheres, each moving linearly from
    p_world (shutter open) by v_world * exposure_s, rendered with Cycles motion blur. Returns the
    collection (hidden per view with "particles": false)."""
    coll = bpy.data.collections.new("particles")
    bpy.context.scene.collection.children.link(coll)
    water = bpy.data.materials.new("water_drop")
    water.use_nodes = True
    nt = water.node_tree
    nt.nodes.clear()
    glass = nt.nodes.new("ShaderNodeBsdfGlass")
    glass.inputs["IOR"].default_value = 1.333
    glass.inputs["Roughness"].default_value = 0.0
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(glass.outputs[0], out.inputs["Surface"])
    flake = bpy.data.materials.new("snow_flake")
    flake.use_nodes = True
    nt = flake.node_tree
    nt.nodes.clear()
    diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (0.9, 0.9, 0.92, 1.0)
    trans = nt.nodes.new("ShaderNodeBsdfTranslucent")
    trans.inputs["Color"].default_value = (0.9, 0.9, 0.92, 1.0)
    mix = nt.nodes.new("ShaderNodeMixShader")
    mix.inputs["Fac"].default_value = 0.5
    nt.links.new(diffuse.outputs[0], mix.inputs[1])
    nt.links.new(trans.outputs[0], mix.inputs[2])
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(mix.outputs[0], out.inputs["Surface"])
    meshes = {}
    dt = particles["exposure_s"]
    for i, p in enumerate(particles["items"]):
        kind = p["kind"]
        if kind not in meshes:
            bm = bmesh.new()
            bmesh.ops.create_icosphere(bm, subdivisions=2, radius=1.0)
            mesh = bpy.data.meshes.new("particle_" + kind)
            for f in bm.faces:
                f.smooth = True
            bm.to_mesh(mesh)
            bm.free()
            mesh.materials.append(water if kind == "rain" else flake)
            meshes[kind] = mesh
        obj = bpy.data.objects.new(f"particle{i}", meshes[kind])
        obj.scale = (p["radius_m"],) * 3
        p0 = Vector(p["p_world"])
        p1 = p0 + Vector(p["v_world"]) * dt
        obj.location = p0
        obj.keyframe_insert("location", frame=1)
        obj.location = p1
        obj.keyframe_insert("location", frame=2)
        for fc in obj.animation_data.action.fcurves:
            for kp in fc.keyframe_points:
                kp.interpolation = "LINEAR"
        coll.objects.link(obj)
    scene = bpy.context.scene
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 1.0  # frames: exactly frame 1 -> 2, i.e. the exposure
    scene.cycles.motion_blur_position = "START"
    return coll


def run(job):
    t0 = time.time()
    out_dir = job["output_dir"]
    scene_file = job["scene_file"]
    spec = job["scene"]
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene

    materials_spec = Params(spec["materials"], scene_file + ":/materials")
    materials = {}
    for name in sorted(materials_spec.data):
        materials[name] = build_material(name, materials_spec.child(name), job["surface"])
    layout = Params(spec["layout"], scene_file + ":/layout")
    collection = bpy.data.collections.new("scene")
    scene.collection.children.link(collection)
    builder = Builder(materials, collection)
    try:
        LAYOUTS[spec["type"]](builder, layout, random.Random(spec["seed"]))
    except SpecError as e:
        if e.where == "materials":
            raise SpecError(scene_file + ":/materials", e.what)
        raise
    n_markers = add_markers(job.get("markers", []))
    particle_coll = add_particles(job["particles"]) if job.get("particles") else None
    setup_lights(job["lights"])

    cam_spec = job["camera"]
    cam_data = bpy.data.cameras.new("camera")
    cam_data.sensor_fit = "HORIZONTAL"
    cam_data.sensor_width = cam_spec["sensor_width_mm"]
    cam_data.lens = cam_spec["focal_length_mm"]
    cam_data.shift_x = 0.0
    cam_data.shift_y = 0.0
    cam_data.clip_start = cam_spec["clip_start_m"]
    cam_data.clip_end = cam_spec["clip_end_m"]
    cam = bpy.data.objects.new("camera", cam_data)
    scene.collection.objects.link(cam)
    scene.camera = cam

    render = job["render"]
    image_dir, depth_dir = job["outputs"]["images"], job["outputs"]["depth"]
    fo = setup_render(render, out_dir, depth_dir)
    os.makedirs(os.path.join(out_dir, image_dir), exist_ok=True)
    os.makedirs(os.path.join(out_dir, depth_dir), exist_ok=True)
    t_setup = time.time() - t0

    views_out = []
    times = []
    W, H = render["width"], render["height"]
    for i, view in enumerate(cam_spec["views"]):
        t1 = time.time()
        cam.matrix_world = blender_from_opencv(view["camera_from_world"])
        bpy.context.view_layer.update()
        # Particle motion is keyed on frames 1 -> 2 (the shutter); plain renders use one frame per view.
        frame = 1 if particle_coll is not None else i + 1
        scene.frame_set(frame)
        if particle_coll is not None:
            particle_coll.hide_render = not view.get("particles", True)
        if render["engine"] == "cycles":
            scene.cycles.seed = view.get("seed", render["seed"])
        fo.file_slots[0].path = view["name"] + "_"
        scene.render.filepath = os.path.join(out_dir, image_dir, view["name"] + ".png")
        bpy.ops.render.render(write_still=True)
        produced = os.path.join(out_dir, depth_dir, f"{view['name']}_{frame:04d}.exr")
        os.replace(produced, os.path.join(out_dir, depth_dir, view["name"] + ".exr"))
        fx, fy, cx, cy = intrinsics(cam_data, W, H)
        views_out.append({"name": view["name"], "width": W, "height": H, "fx": fx, "fy": fy, "cx": cx, "cy": cy,
                          "camera_from_world": opencv_from_blender(cam),
                          "time_s": view["time_s"], "exposure_s": view["exposure_s"],
                          "focal_length_mm": cam_data.lens})
        times.append(time.time() - t1)
        print(f"weathergs: rendered view {view['name']} ({i + 1}/{len(cam_spec['views'])}) in {times[-1]:.2f} s",
              flush=True)

    with open(os.path.join(out_dir, "cameras.json"), "w") as f:
        json.dump({"views": views_out}, f, indent=1)
    with open(os.path.join(out_dir, "render_log.json"), "w") as f:
        json.dump({"blender": bpy.app.version_string, "engine": render["engine"], "objects": builder.count,
                   "materials": len(materials), "markers": n_markers, "setup_seconds": t_setup,
                   "view_seconds": times, "total_seconds": time.time() - t0}, f, indent=1)


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(argv) != 1:
        raise SystemExit("usage: blender -b --python render_scene.py -- JOB.json")
    with open(argv[0]) as f:
        job = json.load(f)
    try:
        run(job)
    except SpecError as e:
        with open(os.path.join(job["output_dir"], "error.json"), "w") as f:
            json.dump({"where": e.where, "what": e.what}, f)
        raise
    except Exception as e:
        with open(os.path.join(job["output_dir"], "error.json"), "w") as f:
            json.dump({"where": "blender_scripts/render_scene.py",
                       "what": f"{type(e).__name__}: {e}\n{traceback.format_exc()}"}, f)
        raise


if __name__ == "__main__":
    main()
