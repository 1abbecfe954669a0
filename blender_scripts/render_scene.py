# Renders one weathergs scene variant headless in Blender 3.4 (EEVEE or Cycles).
#
#   blender -b --factory-startup --python-exit-code 1 --python render_scene.py -- JOB.json
#
# Talks to C++ only through files (docs/scenes.md, "Blender job files"):
#   in : JOB.json  {"scene": {...}, "scene_file": "...", "surface": {...}, "lights": {...},
#                   "render": {...}, "camera": {... "clip_start_m", "clip_end_m"}, "markers": [...],
#                   "outputs": {"images": IMG, "depth": DEPTH}, "output_dir": "..."}
#   out: <output_dir>/IMG/<view>.png         8-bit sRGB (view transform "Standard"); with
#                                            render.float_images: IMG/<view>.exr, scene-linear float32
#        <output_dir>/DEPTH/<view>.exr       planar camera z, float32, R=G=B, background 65504 (EEVEE)
# Folder names and the clip range come from the job: capture/blender.cc owns them.
#        <output_dir>/cameras.json           docs/formats.md cameras, recomputed from Blender's camera
#        <output_dir>/render_log.json        timings and object counts
#        <output_dir>/error.json             only on failure: {"where": "...", "what": "..."}
# The layout and material parameters of the scene spec are validated here (unknown keys are errors);
# everything else was validated by the C++ side before the job was written.
# The code lives in the weathergs_blender package next to this file (one module per layout, shared
# materials, builder and render setup).
import json
import os
import random
import sys
import time
import traceback

import bpy

sys.dont_write_bytecode = True  # never write __pycache__ into a checkout or an install prefix
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from weathergs_blender.builder import Builder  # noqa: E402
from weathergs_blender.layouts import LAYOUTS  # noqa: E402
from weathergs_blender.materials import build_material  # noqa: E402
from weathergs_blender.render import (CoverageMode, add_lens_drops, add_markers, add_particles, blender_from_opencv,  # noqa: E402
                                      intrinsics, opencv_from_blender, setup_lights, setup_render)
from weathergs_blender.spec import Params, SpecError  # noqa: E402


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
    if cam_spec.get("dof"):
        # Thin-lens depth of field with the camera's lens data (validation renders; the datasets'
        # renders are pinholes and the generator applies the lens).
        cam_data.dof.use_dof = True
        cam_data.dof.focus_distance = cam_spec["dof"]["focus_distance_m"]
        cam_data.dof.aperture_fstop = cam_spec["dof"]["f_number"]
    cam = bpy.data.objects.new("camera", cam_data)
    scene.collection.objects.link(cam)
    scene.camera = cam
    lens_coll, plugs_coll, glass_coll = add_lens_drops(job["lens_drops"], cam) if job.get("lens_drops") else (None,) * 3

    render = job["render"]
    image_dir, depth_dir = job["outputs"]["images"], job["outputs"]["depth"]
    fo = setup_render(render, out_dir, depth_dir)
    os.makedirs(os.path.join(out_dir, image_dir), exist_ok=True)
    os.makedirs(os.path.join(out_dir, depth_dir), exist_ok=True)
    t_setup = time.time() - t0

    # Only validation jobs ask for coverage views: dataset renders never touch those settings.
    coverage = CoverageMode(collection.name) if any(v.get("coverage") for v in cam_spec["views"]) else None
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
        if coverage is not None:
            coverage.set(bool(view.get("coverage", False)))
        if lens_coll is not None:
            lens_coll.hide_render = not view.get("lens", True)
        if glass_coll is not None:  # the cover glass, its holes plugged where no drop is shown
            glass_coll.hide_render = not view.get("glass", True)
            plugs_coll.hide_render = glass_coll.hide_render or not lens_coll.hide_render
        if render["engine"] == "cycles":
            scene.cycles.seed = view.get("seed", render["seed"])
            # A view may ask for its own sample count (the validation's coverage view: its Monte
            # Carlo noise decides how well the streak ends are measured).
            scene.cycles.samples = view.get("samples", render["samples"])
        fo.file_slots[0].path = view["name"] + "_"
        ext = ".exr" if render.get("float_images", False) else ".png"
        scene.render.filepath = os.path.join(out_dir, image_dir, view["name"] + ext)
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
