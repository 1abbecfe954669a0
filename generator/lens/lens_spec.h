// The `effects.lens_droplets` object of the weather spec (docs/formats.md) and its documented
// extras (docs/lens_droplets.md). Parsing is strict: unknown keys and out-of-range values are
// InputError naming the JSON pointer; every field below has a validated default.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <string>

#include "core/json_reader.h"
#include "generator/lens/optics.h"

namespace weathergs::generator::lens {

enum class Attach { kLens, kWindow };
// Which side of the glass the water sits on. kScene: the side away from the camera (rain on a lens
// cover or a window; camera rays enter a drop through its flat base). kCamera: the side facing the
// camera (condensation; camera rays enter through the curved cap).
enum class DropSide { kScene, kCamera };
enum class RadiusDistribution { kLogUniform, kUniform };
enum class CapGeometry { kAnalytic, kTriangles };
// masks/lens: "perceptible" = where the drops change the 8-bit image by more than
// mask_min_change_levels in some channel (what a method would see; defocused veils that change
// nothing visible stay unmasked); "coverage" = where the blurred glass coverage >= mask_threshold.
enum class LensMaskRule { kPerceptible, kCoverage };

const char* to_string(Attach a);
const char* to_string(DropSide s);
const char* to_string(RadiusDistribution d);
const char* to_string(CapGeometry g);
const char* to_string(LensMaskRule r);

// A window pane fixed in the world (attach "window"). normal_world points away from the cameras'
// side; drops sit on the side named by drop_side. Drops are sampled on a size_m rectangle around
// center_world whose "down" axis is -up_world projected onto the pane (gravity, world +z up).
struct WindowPose {
  Eigen::Vector3d center_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal_world = Eigen::Vector3d::UnitY();
  Eigen::Vector3d up_world = Eigen::Vector3d::UnitZ();
  std::array<double, 2> size_m = {1.0, 1.0};  // width, height
};

struct LensDropletSpec {
  int count = 60;                                 // drops on the sampled glass area
  std::array<double, 2> radius_mm = {0.5, 3.0};   // outline radius range (see docs), mm
  RadiusDistribution radius_distribution = RadiusDistribution::kLogUniform;
  std::array<double, 2> contact_angle_deg = {70, 70};  // uniform in [lo, hi], 0 < lo <= hi < 180
  double glass_distance_m = 0.03;                 // pinhole to glass along the optical axis
  // The glass under the drops: a slab on the camera's side of their bases (0: thin glass, no
  // refraction of its own; the paper style's). Physical style, lens attach: 1 mm unless given.
  double glass_thickness_mm = 0;
  double glass_refractive_index = kCrownGlassRefractiveIndex;
  Attach attach = Attach::kLens;
  DropSide drop_side = DropSide::kScene;
  std::array<double, 2> glass_tilt_deg = {0, 0};  // lens attach: rotation about camera x, then y
  std::optional<WindowPose> window;               // window attach; default from the first camera
  double refractive_index = 1.333;                // water at 20 C, visible light
  double slide_speed_mm_s = 0;                    // gravity sliding speed of large drops
  double slide_min_radius_mm = 1.5;               // smaller drops stay pinned
  int samples_per_pixel = 4;                      // stratified, seeded per pixel
  int max_bounces = 4;                            // total internal reflections followed per path
  CapGeometry geometry = CapGeometry::kAnalytic;
  int cap_segments = 48;                          // triangles geometry: segments around a cap
  std::optional<std::array<double, 3>> environment_radiance;  // unset: the view's mean radiance, or
  bool environment_sky = false;  // ... the dataset's sky radiance estimate ("sky"; physical style's default)
  // Light the drops send back towards the camera (trace_path's camera_weight) meets the camera's own
  // front: its radiance, linear RGB; unset ("environment"): the environment radiance as any other
  // unfollowed light (the paper style's, and the window attach's, where the room lies behind).
  std::optional<std::array<double, 3>> camera_radiance;
  bool defocus = true;                            // thin-lens blur of the glass when known
  LensMaskRule mask_rule = LensMaskRule::kPerceptible;
  double mask_min_change_levels = 4;              // perceptible rule: 8-bit sRGB levels (> this)
  double mask_threshold = 0.1;                    // coverage rule: blurred coverage >= this
  double sampling_margin = 0.1;                   // lens attach: extra glass area sampled per side
};

// Parses the object at `reader` (e.g. the weather spec's /effects/lens_droplets). Calls finish().
LensDropletSpec parse_lens_droplet_spec(const JsonReader& reader);
// Throws InputError(where, ...) naming the field, its value and the rule it broke.
void validate_lens_droplet_spec(const LensDropletSpec& spec, const std::string& where);
// Every field, defaults included: what a dataset records as the resolved spec. Parsing it again
// gives the same spec.
Json lens_droplet_spec_to_json(const LensDropletSpec& spec);

}  // namespace weathergs::generator::lens
