// Headless Blender renders of a scene variant (blender_scripts/render_scene.py). C++ and the script
// talk only through files: a JSON job in, clean PNGs, raw depth EXRs and cameras.json out
// (docs/scenes.md, "Blender job files").
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/json_reader.h"
#include "capture/process.h"
#include "capture/scene_spec.h"

namespace weathergs::capture {

struct BlenderOptions {
  std::string executable = "blender";  // name on PATH or a path
  std::string script;                  // blender_scripts/render_scene.py (required; apps/resources.h finds it)
  double timeout_s = 0;  // 0 = no limit
  // Only the first `max_views` views of the profile (0 = all): tests and previews.
  int max_views = 0;
  // Threads Blender may use (0 = all cores): a Cycles render runs as that many one-thread processes
  // side by side, each on its own views, so its pixels never depend on it; EEVEE runs as one process
  // with `-t` and llvmpipe's LP_NUM_THREADS set to it (and is not repeatable under any setting).
  // `weathergs --threads N generate` sets it to N.
  int threads = 0;

  void validate() const;  // InputError naming the field (executable and script set, timeout, max_views and threads >= 0)
};

// A small emissive magenta sphere (sRGB 255, 0, 255 under the "Standard" view transform): projected
// with cameras.json it must land where Blender drew it (tests/capture/conventions_test.cc).
struct Marker {
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  double radius_m = 0.05;
};

// Runs `script` (render_scene.py) on the job file in background Blender with factory settings; an
// exception in the script exits with code 1. The one command line every caller uses. Blender's
// temporary files go to `<folder of job_path>/blender_tmp_XXXXXX`, removed when the run ends.
// threads > 0 caps Blender and llvmpipe at that many threads (BlenderOptions::threads).
ProcessResult run_blender_job(const std::string& executable, const std::string& script, const std::string& job_path,
                              const std::string& what, const ProcessOptions& options, int threads = 0);

// The job file for the script, without output_dir (the cache key is a hash of it).
Json blender_job(const SceneSpec& scene, const VariantSpec& variant, const ProfileSpec& profile,
                 const std::vector<Camera>& cameras, const std::vector<Marker>& markers);

struct RenderSummary {
  double seconds = 0;        // wall time of the Blender process
  double first_view_s = 0;   // includes EEVEE's shader compilation
  int views = 0, objects = 0;
  int processes = 1;         // Blender processes side by side (one-thread Cycles processes)
};

// Renders a clean dataset of `variant` (its surface state and lights, no airborne weather) into
// out_dir, atomically: dataset.json (weather "clear", generator.surface = the variant's surface),
// cameras.json (recomputed from Blender's camera and checked against the requested path), clean/ and
// images/ (the same PNGs), depth/ (planar z, EXR channel Z, background +inf) and logs/ (job and
// Blender's output). Blender missing or failing, or a bad layout/material spec, is an InputError and
// leaves nothing at out_dir.
RenderSummary render_clean_dataset(const SceneSpec& scene, const std::string& variant, const std::string& profile,
                                   const std::string& out_dir, const BlenderOptions& options,
                                   const std::vector<Marker>& markers = {});

}  // namespace weathergs::capture
