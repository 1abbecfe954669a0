"""Lights, camera conventions (OpenCV <-> Blender), render settings, markers and particles."""
import math
import os

import bmesh
import bpy
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


def add_particles(particles):
    """Airborne particles for the path-tracer validation only (docs/scenes.md): rain drops as water
    spheres (glass, IOR 1.333), snow flakes as Lambertian spheres (particles["snow"]: albedo,
    opacity), each moving linearly from
    p_world (shutter open) by v_world * exposure_s, rendered with Cycles motion blur. Returns the
    collection (hidden per view with "particles": false)."""
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


def add_lens_drops(lens, camera):
    """Water drops on the cover glass for the path-tracer validation of the lens-drop layer
    (docs/lens_droplets.md): each drop a spherical cap closed by its flat base, water (glass BSDF,
    IOR lens["refractive_index"]), built in OpenCV camera coordinates from the generator's drop list
    and parented to the camera. No glass plate: a thin parallel plate turns no ray (the generator's
    model), and a water base coincident with a glass face would leave Cycles two surfaces at one depth.
    Returns the collection (hidden per view with "lens": false)."""
    coll = bpy.data.collections.new("lens_drops")
    bpy.context.scene.collection.children.link(coll)
    water = water_material("lens_water", lens["refractive_index"])
    for i, d in enumerate(lens["drops"]):
        cx, cy, cz = d["base_center_camera_m"]  # OpenCV camera frame; the glass is the plane z = cz
        R = d["sphere_radius_m"]
        theta = math.radians(d["contact_angle_deg"])
        bm = bmesh.new()
        bmesh.ops.create_uvsphere(bm, u_segments=96, v_segments=48, radius=R)
        # The ball's centre lies R cos(theta) behind the glass (towards the camera) for a cap bulging
        # towards the scene; keep what is beyond the glass and close it with the flat base.
        bmesh.ops.translate(bm, verts=bm.verts, vec=(cx, cy, cz - R * math.cos(theta)))
        cut = bmesh.ops.bisect_plane(bm, geom=bm.verts[:] + bm.edges[:] + bm.faces[:], dist=1e-9,
                                     plane_co=(0.0, 0.0, cz), plane_no=(0.0, 0.0, 1.0), clear_inner=True)
        edges = [e for e in cut["geom_cut"] if isinstance(e, bmesh.types.BMEdge)]
        bmesh.ops.edgeloop_fill(bm, edges=edges)
        for v in bm.verts:  # OpenCV camera -> Blender camera axes (x, -y, -z)
            v.co = Vector((v.co.x, -v.co.y, -v.co.z))
        bm.normal_update()  # recalc_face_normals orients by the stored normals: refresh them first
        bmesh.ops.recalc_face_normals(bm, faces=bm.faces)
        for f in bm.faces:
            f.smooth = len(f.verts) < 5  # the base polygon stays flat
        mesh = bpy.data.meshes.new(f"lens_drop{i}")
        bm.to_mesh(mesh)
        bm.free()
        mesh.materials.append(water)
        obj = bpy.data.objects.new(f"lens_drop{i}", mesh)
        obj.parent = camera
        coll.objects.link(obj)
    return coll
