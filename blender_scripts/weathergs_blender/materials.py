"""Materials: a pattern plus colours and scales from the scene spec, and the surface state (snow,
wetness, puddles) of a variant."""
import bpy

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
    # Cycles (3.4) builds its light distribution over emissive meshes in an order that changes from
    # process to process, and with it which samples go where: 75 % of a lantern street's pixels
    # differed between two renders. Emitters not sampled as lights are found by the paths alone, the
    # same way in every run (docs/scenes.md, "Repeatability").
    mat.cycles.sample_as_light = False
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
