// Scene specs (scenes/*.json, docs/scenes.md): layout, materials, lights, the forward-facing camera
// path, render profiles, the test split rule and one variant (surface state, lights, weather spec)
// per weather. The C++ side validates everything except `layout` and `materials`, which belong to
// the Blender script (blender_scripts/render_scene.py validates them just as strictly and reports
// errors with the same file:/pointer locations).
#pragma once

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/json_reader.h"

namespace weathergs::capture {

struct ProfileSpec {
  std::string name;
  int width = 0, height = 0;  // pixels; width >= height (Blender sensor fit horizontal)
  int views = 0;
  int samples = 0;            // EEVEE TAA samples or Cycles samples per pixel
  std::string engine = "eevee";  // "eevee" (noise-free, the default) or "cycles"
};

// LLFF-like forward-facing path: views on an elliptic spiral around position_m in the plane facing
// look_at_m, all looking at look_at_m.
struct CameraPathSpec {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d look_at_m = Eigen::Vector3d::UnitY();
  Eigen::Vector2d radius_m = {1.0, 0.5};  // spiral radii along camera right and up
  double depth_m = 0.5;                   // forward/backward excursion along the viewing direction
  double turns = 2.0;
  double focal_length_mm = 24.0;
  double sensor_width_mm = 36.0;
  double exposure_s = 1.0 / 60.0;
  double frame_interval_s = 0.5;  // time_s of view k is k * frame_interval_s
  // A real lens (both or neither): f-number and focus distance written into every view. The focal
  // length is focal_length_mm: with sensor_width_mm it sets the field of view as well.
  std::optional<double> f_number, focus_distance_m;
};

// The closest pair of camera centres of a profile must be at least this fraction of the path size
// (the largest distance between two centres). 0.02: at 16 views on a two-turn path the spacing of
// neighbouring views is ~0.1-0.2 of the path, so 0.02 only rejects coinciding or nearly coinciding views.
inline constexpr double kMinCameraSeparationFraction = 0.02;
// Closest pair of camera centres divided by the largest distance between two centres (1 for < 2 views).
double min_camera_separation_fraction(const std::vector<Camera>& cameras);

struct VariantSpec {
  std::string name;   // e.g. "snow"; the dataset's `weather`
  Json surface;       // normalized surface state for Blender: {"kind": "snow"|"rain"|"clear", ...}
  Json lights;        // base lights with this variant's overrides applied
  Json weather;       // weather spec for the generator (validated there); null = no airborne weather
};

struct SceneSpec {
  std::string file;  // where it was read from (error messages, relative paths)
  std::string name, type, description;
  uint64_t seed = 0;
  Json layout, materials;  // validated by the Blender script
  Json lights;             // normalized
  CameraPathSpec camera;
  std::map<std::string, ProfileSpec> profiles;
  int split_every = 8;     // LLFF rule: 0-based index % split_every == 0 is a test view
  std::map<std::string, VariantSpec> variants;

  const ProfileSpec& profile(const std::string& name) const;  // InputError naming the choices
  // "clear" is always available (base lights, no surface state, no weather).
  VariantSpec variant(const std::string& name) const;
};

// Scene types the Blender script knows.
const std::vector<std::string>& scene_types();

SceneSpec read_scene_spec(const std::string& path);

// The cameras of a profile in our conventions (OpenCV axes, pixel-corner origin), views "000", ...
std::vector<Camera> scene_cameras(const SceneSpec& scene, const ProfileSpec& profile);

}  // namespace weathergs::capture
