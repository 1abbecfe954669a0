"""Lights, camera conventions (OpenCV <-> Blender), render settings, markers and particles."""
import math
import os

import bmesh
import bpy
import numpy as np
from mathutils import Matrix, Vector

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
    if render.get("float_images", False):
        # Scene-linear float32 (validation against the C++ layers below 8-bit quantization).
        scene.render.image_settings.file_format = "OPEN_EXR"
        scene.render.image_settings.color_mode = "RGB"
        scene.render.image_settings.color_depth = "32"
        scene.render.image_settings.exr_codec = "ZIP"
    else:
        scene.render.image_settings.file_format = "PNG"
        scene.render.image_settings.color_mode = "RGB"
        scene.render.image_settings.color_depth = "8"
    scene.render.dither_intensity = 0.0  # dithering is noise: keep renders of one view identical
    # No metadata in the written files: the date and render times would make every render a new file
    # (the C++ side re-encodes the PNGs as well).
    scene.render.use_stamp = False
    for key in dir(scene.render):
        if key.startswith("use_stamp_") and isinstance(getattr(scene.render, key), bool):
            setattr(scene.render, key, False)
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


def emission_material(name, rgb):
    """An emitter of strength 1 and colour `rgb`: it shows exactly rgb, whatever lights it."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    em = nt.nodes.new("ShaderNodeEmission")
    em.inputs["Color"].default_value = (*rgb, 1.0)
    em.inputs["Strength"].default_value = 1.0
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(em.outputs[0], out.inputs["Surface"])
    return mat


def add_markers(markers):
    if not markers:
        return 0
    mat = emission_material("marker", (1.0, 0.0, 1.0))
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


def water_material(name, ior):
    """Clear water: a smooth glass BSDF of refractive index `ior`."""
    water = bpy.data.materials.new(name)
    water.use_nodes = True
    nt = water.node_tree
    nt.nodes.clear()
    glass = nt.nodes.new("ShaderNodeBsdfGlass")
    glass.inputs["IOR"].default_value = ior
    glass.inputs["Roughness"].default_value = 0.0
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(glass.outputs[0], out.inputs["Surface"])
    return water


# Every particle is an instance of one icosphere of this many subdivisions (320 faces): instances
# cost no memory per face, so even 10^5 flakes need no coarser mesh.
SPHERE_SUBDIVISIONS = 3


def sphere_template(name, subdivisions, material):
    """A unit icosphere (smooth-shaded, `material`) scaled so that its mean projected area is pi (a
    polyhedron's is a quarter of its surface, Cauchy's formula): the tessellated sphere covers as much
    of the image, on average, as the true one (unscaled, 80 faces cover 0.928 of it)."""
    bm = bmesh.new()
    bmesh.ops.create_icosphere(bm, subdivisions=subdivisions, radius=1.0)
    scale = math.sqrt(4.0 * math.pi / sum(f.calc_area() for f in bm.faces))
    bmesh.ops.scale(bm, vec=(scale,) * 3, verts=bm.verts)
    for f in bm.faces:
        f.smooth = True
    mesh = bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    bm.free()
    mesh.materials.append(material)
    return bpy.data.objects.new(name, mesh)


def moving_spheres(name, items, exposure_s, material):
    """All spheres of one kind as instances of one unit sphere (sphere_template) on the points of a
    mesh (geometry nodes; scale = the point's radius attribute) whose shape key moves every point
    linearly from p_world (shutter open, frame 1) to p_world + v_world * exposure_s (frame 2): Cycles
    blurs each instance as an object moving on that line, and 10^5 particles build in seconds where
    one object each took tens of minutes. Instances, not one merged mesh: Cycles intersects an
    instance in its own space, where the sphere has radius ~1; a merged world-space mesh of millimetre
    drops metres from the origin made the drops of rain 25 mm/h darken the view 3.6x as much as
    instanced ones (128 samples). Returns the points' object (the template is not in the scene)."""
    template = sphere_template(name + "_sphere", SPHERE_SUBDIVISIONS, material)
    p0 = np.array([p["p_world"] for p in items], dtype=np.float64)
    p1 = p0 + np.array([p["v_world"] for p in items], dtype=np.float64) * exposure_s
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(items))
    mesh.vertices.foreach_set("co", p0.astype(np.float32).ravel())
    radius = mesh.attributes.new("radius", "FLOAT", "POINT")
    radius.data.foreach_set("value", np.array([p["radius_m"] for p in items], dtype=np.float32))
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    obj.shape_key_add(name="open")
    key = obj.shape_key_add(name="close")
    key.data.foreach_set("co", p1.astype(np.float32).ravel())
    key.value = 0.0
    key.keyframe_insert("value", frame=1)
    key.value = 1.0
    key.keyframe_insert("value", frame=2)
    for fc in mesh.shape_keys.animation_data.action.fcurves:
        for kp in fc.keyframe_points:
            kp.interpolation = "LINEAR"
    tree = bpy.data.node_groups.new(name + "_instances", "GeometryNodeTree")
    tree.inputs.new("NodeSocketGeometry", "Geometry")
    tree.outputs.new("NodeSocketGeometry", "Geometry")
    group_in, group_out = tree.nodes.new("NodeGroupInput"), tree.nodes.new("NodeGroupOutput")
    info = tree.nodes.new("GeometryNodeObjectInfo")
    info.inputs["Object"].default_value = template
    scale = tree.nodes.new("GeometryNodeInputNamedAttribute")
    scale.data_type = "FLOAT"
    scale.inputs["Name"].default_value = "radius"
    instances = tree.nodes.new("GeometryNodeInstanceOnPoints")
    tree.links.new(group_in.outputs["Geometry"], instances.inputs["Points"])
    tree.links.new(info.outputs["Geometry"], instances.inputs["Instance"])
    # 3.4 lists one output per data type, all named "Attribute": link the float one.
    tree.links.new(next(o for o in scale.outputs if o.identifier == "Attribute_Float"), instances.inputs["Scale"])
    tree.links.new(instances.outputs["Instances"], group_out.inputs["Geometry"])
    obj.modifiers.new("instances", "NODES").node_group = tree
    obj.cycles.use_motion_blur = True
    return obj


def add_particles(particles):
    """Airborne particles for the path-tracer validation only (docs/scenes.md): rain drops as water
    spheres (glass, IOR 1.333), snow flakes as Lambertian spheres (particles["snow"]: albedo,
    opacity), each moving linearly from p_world (shutter open) by v_world * exposure_s, rendered with
    Cycles motion blur (moving_spheres). Returns the collection (hidden per view with "particles":
    false)."""
    coll = bpy.data.collections.new("particles")
    bpy.context.scene.collection.children.link(coll)
    water = water_material("water_drop", 1.333)
    # Snow: the generator's flake, a Lambertian sphere of the spec's albedo that covers `opacity` of
    # its disk (the rest transparent).
    snow = particles.get("snow", {"albedo": 0.9, "opacity": 1.0})
    flake = bpy.data.materials.new("snow_flake")
    flake.use_nodes = True
    nt = flake.node_tree
    nt.nodes.clear()
    diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
    a = snow["albedo"]
    diffuse.inputs["Color"].default_value = (a, a, a, 1.0)
    diffuse.inputs["Roughness"].default_value = 0.0
    clear = nt.nodes.new("ShaderNodeBsdfTransparent")
    mix = nt.nodes.new("ShaderNodeMixShader")
    # One scattering surface per flake, as the generator's: the front face covers `opacity`, the back
    # face is fully transparent (else light passing the front would meet a second, inner face).
    geometry = nt.nodes.new("ShaderNodeNewGeometry")
    front = nt.nodes.new("ShaderNodeMath")
    front.operation = "MULTIPLY_ADD"  # opacity * (-backfacing) + opacity
    front.inputs[1].default_value = -snow["opacity"]
    front.inputs[2].default_value = snow["opacity"]
    nt.links.new(geometry.outputs["Backfacing"], front.inputs[0])
    nt.links.new(front.outputs[0], mix.inputs["Fac"])
    nt.links.new(clear.outputs[0], mix.inputs[1])
    nt.links.new(diffuse.outputs[0], mix.inputs[2])
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(mix.outputs[0], out.inputs["Surface"])
    dt = particles["exposure_s"]
    unknown = {p["kind"] for p in particles["items"]} - {"rain", "snow"}
    if unknown:
        raise ValueError(f"particles: unknown kinds {sorted(unknown)} (rain and snow are known)")
    for kind in ("rain", "snow"):
        items = [p for p in particles["items"] if p["kind"] == kind]
        if items:
            coll.objects.link(moving_spheres("particles_" + kind, items, dt, water if kind == "rain" else flake))
    scene = bpy.context.scene
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 1.0  # frames: exactly frame 1 -> 2, i.e. the exposure
    scene.cycles.motion_blur_position = "START"
    return coll


def add_lens_drops(lens, camera):
    """Water drops on the cover glass for the path-tracer validation of the lens-drop layer
    (docs/lens_droplets.md): each drop a spherical cap closed by its flat base, water (glass BSDF,
    IOR lens["refractive_index"]), built in OpenCV camera coordinates from the generator's drop list
    and parented to the camera.

    With lens["glass_plate"] ({"thickness_m", "refractive_index", "half_size_m"}) the cover glass is
    there too: a slab on the camera side of the drops whose outer face has a hole under each drop.
    Cycles tracks no nested media, so every surface carries the index ratio of the two media it
    separates, its normal pointing into the first: the slab's faces air/glass, a drop's base
    glass/water (normal towards the camera, ratio n_water / n_glass), its cap water/air. Where no drop
    sits (views with "lens": false) plugs of glass/air fill the holes. Without a plate the base is
    air/water (the generator's thin glass). lens["camera_body"] ({"half_size_m"}) adds the camera's
    dark front around the lens. Returns (drops, plugs, plate) collections; plugs and plate
    are None without a plate."""
    coll = bpy.data.collections.new("lens_drops")
    bpy.context.scene.collection.children.link(coll)
    n_water = lens["refractive_index"]
    water = water_material("lens_water", n_water)
    plate = lens.get("glass_plate")
    if plate:
        n_glass = plate["refractive_index"]
        interface = water_material("glass_water", n_water / n_glass)
    rings = []  # per drop: its base polygon (OpenCV camera coordinates), shared with the plate's holes

    def to_blender(bm):
        for v in bm.verts:  # OpenCV camera -> Blender camera axes (x, -y, -z): a rotation, no mirror
            v.co = Vector((v.co.x, -v.co.y, -v.co.z))

    def orient(bm, want):  # want(face) -> the direction its normal must take (OpenCV frame)
        bm.normal_update()
        flip = [f for f in bm.faces if f.normal.dot(want(f)) < 0]
        if flip:
            bmesh.ops.reverse_faces(bm, faces=flip)

    def ring_edges(bm, ring):  # a drop's base polygon as edges of bm, its vertices shared
        verts = {}

        def vert(co):
            key = (round(co.x, 12), round(co.y, 12))
            if key not in verts:
                verts[key] = bm.verts.new(co)
            return verts[key]
        return [bm.edges.new((vert(a), vert(b))) for a, b in ring]

    def new_object(name, bm, materials, parent_coll):
        to_blender(bm)
        bm.normal_update()
        mesh = bpy.data.meshes.new(name)
        bm.to_mesh(mesh)
        bm.free()
        for m in materials:
            mesh.materials.append(m)
        obj = bpy.data.objects.new(name, mesh)
        obj.parent = camera
        parent_coll.objects.link(obj)
        return obj

    cz = None
    for i, d in enumerate(lens["drops"]):
        cx, cy, dz = d["base_center_camera_m"]  # OpenCV camera frame; the glass is the plane z = dz
        if cz is None:
            cz = dz
        elif plate and abs(dz - cz) > 1e-12:
            raise ValueError("glass_plate: the drops' bases must lie on one untilted glass plane")
        R = d["sphere_radius_m"]
        theta = math.radians(d["contact_angle_deg"])
        bm = bmesh.new()
        bmesh.ops.create_uvsphere(bm, u_segments=96, v_segments=48, radius=R)
        # The ball's centre lies R cos(theta) behind the glass (towards the camera) for a cap bulging
        # towards the scene; keep what is beyond the glass and close it with the flat base.
        bmesh.ops.translate(bm, verts=bm.verts, vec=(cx, cy, dz - R * math.cos(theta)))
        cut = bmesh.ops.bisect_plane(bm, geom=bm.verts[:] + bm.edges[:] + bm.faces[:], dist=1e-9,
                                     plane_co=(0.0, 0.0, dz), plane_no=(0.0, 0.0, 1.0), clear_inner=True)
        edges = [e for e in cut["geom_cut"] if isinstance(e, bmesh.types.BMEdge)]
        fill = bmesh.ops.edgeloop_fill(bm, edges=edges)
        base = [f for f in fill["faces"]]
        rings.append([(e.verts[0].co.copy(), e.verts[1].co.copy()) for e in edges])
        centre = Vector((cx, cy, dz - R * math.cos(theta)))
        # Cap faces point away from the ball's centre (into the air), the base towards the camera.
        orient(bm, lambda f: Vector((0.0, 0.0, -1.0)) if f in base else f.calc_center_median() - centre)
        for f in bm.faces:
            f.smooth = f not in base  # the base polygon stays flat
            f.material_index = 1 if (plate and f in base) else 0
        new_object(f"lens_drop{i}", bm, [water, interface] if plate else [water], coll)
    body = lens.get("camera_body")
    if body:
        # The camera's body around the lens: what the drops and the glass send back towards the camera
        # meets it (dark), not the sky behind an invisible camera. A black square 1 mm behind the
        # aperture: it meets no camera ray and, that small, shades nothing of the scene measurably.
        housing = bpy.data.materials.new("camera_body")
        housing.use_nodes = True
        bsdf = housing.node_tree.nodes["Principled BSDF"]
        bsdf.inputs["Base Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        bsdf.inputs["Specular"].default_value = 0.0
        bm = bmesh.new()
        b = body["half_size_m"]
        bm.faces.new([bm.verts.new((x, y, -1e-3)) for x, y in [(-b, -b), (b, -b), (b, b), (-b, b)]])
        orient(bm, lambda f: Vector((0.0, 0.0, 1.0)))
        new_object("camera_body", bm, [housing], bpy.context.scene.collection)
    if not plate:
        return coll, None, None

    glass = water_material("cover_glass", n_glass)
    plate_coll = bpy.data.collections.new("cover_glass")
    bpy.context.scene.collection.children.link(plate_coll)
    plugs_coll = bpy.data.collections.new("cover_glass_plugs")
    bpy.context.scene.collection.children.link(plugs_coll)
    if cz is None:
        cz = plate["glass_distance_m"]
    h, near = plate["half_size_m"], cz - plate["thickness_m"]
    bm = bmesh.new()
    corners = [(-h, -h), (h, -h), (h, h), (-h, h)]
    vn = [bm.verts.new((x, y, near)) for x, y in corners]
    vf = [bm.verts.new((x, y, cz)) for x, y in corners]
    bm.faces.new(vn)
    for k in range(4):
        bm.faces.new((vn[k], vn[(k + 1) % 4], vf[(k + 1) % 4], vf[k]))
    outline = [bm.edges.get((vf[k], vf[(k + 1) % 4])) for k in range(4)]  # made with the side faces
    holes = [e for ring in rings for e in ring_edges(bm, ring)]
    # The outer face: the square minus the drops' bases (scanfill treats nested loops as holes).
    bmesh.ops.triangle_fill(bm, use_beauty=True, use_dissolve=False, edges=outline + holes)
    middle = Vector((0.0, 0.0, 0.5 * (near + cz)))
    orient(bm, lambda f: Vector((0.0, 0.0, -1.0)) if abs(f.calc_center_median().z - near) < 1e-12
           else Vector((0.0, 0.0, 1.0)) if abs(f.calc_center_median().z - cz) < 1e-12
           else f.calc_center_median() - middle)
    new_object("cover_glass", bm, [glass], plate_coll)
    for i, ring in enumerate(rings):  # glass/air where the drops' bases would be
        bm = bmesh.new()
        bmesh.ops.edgeloop_fill(bm, edges=ring_edges(bm, ring))
        orient(bm, lambda f: Vector((0.0, 0.0, 1.0)))
        new_object(f"cover_glass_plug{i}", bm, [glass], plugs_coll)
    return coll, plugs_coll, plate_coll


class CoverageMode:
    """Per-view switch for the particles' coverage render of the path-tracer validation: a view with
    "coverage": true renders every particle as an opaque white emitter over a transparent film, the
    scene's geometry as a holdout (it occludes particles behind it and shows nothing itself). The
    float image's RGB (premultiplied) is then the fraction of the exposure and of the lens aperture
    during which a particle covers the pixel: Garg and Nayar's tau / T, the quantity the generator's
    alpha layer holds, free of any shading."""

    def __init__(self, scene_collection_name):
        self.name = scene_collection_name
        self.white = None
        self.exposure = None  # the render's own, restored after a coverage view

    def set(self, on):
        scene = bpy.context.scene
        layer = bpy.context.view_layer
        if on and self.white is None:
            self.white = emission_material("coverage_white", (1.0, 1.0, 1.0))
        scene.render.film_transparent = on
        layer.material_override = self.white if on else None
        layer.layer_collection.children[self.name].holdout = on
        if self.exposure is None:
            self.exposure = scene.view_settings.exposure
        scene.view_settings.exposure = 0.0 if on else self.exposure  # coverage 1 -> pixel value 1

