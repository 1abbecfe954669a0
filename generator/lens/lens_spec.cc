#include "generator/lens/lens_spec.h"

#include <cmath>
#include <sstream>

#include "core/json_fields.h"

namespace weathergs::generator::lens {

const char* to_string(Attach a) { return a == Attach::kLens ? "lens" : "window"; }
const char* to_string(DropSide s) { return s == DropSide::kScene ? "scene" : "camera"; }
const char* to_string(RadiusDistribution d) {
  return d == RadiusDistribution::kLogUniform ? "log_uniform" : "uniform";
}
const char* to_string(CapGeometry g) { return g == CapGeometry::kAnalytic ? "analytic" : "triangles"; }
const char* to_string(LensMaskRule r) { return r == LensMaskRule::kPerceptible ? "perceptible" : "coverage"; }

namespace {

std::string num(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

void require(bool ok, const std::string& where, const std::string& field, const std::string& value,
             const std::string& rule) {
  if (!ok) throw InputError(where + "/" + field, "got " + value + ", expected " + rule);
}

}  // namespace

namespace {

using json_fields::OneOf;
using json_fields::Range;

constexpr auto kWindowFields = [](auto& s, auto& f) {  // every key required but the up direction
  f("center_world", s.center_world);
  f("normal_world", s.normal_world);
  f("up_world", s.up_world, json_fields::Optional{});
  f("size_m", s.size_m);
};

// The one list of the lens_droplets effect's keys; a missing key keeps its documented default.
constexpr auto kLensFields = [](auto& s, auto& f) {
  f("count", s.count);
  f("radius_mm", s.radius_mm, Range{});
  f("radius_distribution", s.radius_distribution, OneOf{RadiusDistribution::kLogUniform, RadiusDistribution::kUniform});
  f("contact_angle_deg", s.contact_angle_deg, Range{});
  f("glass_distance_m", s.glass_distance_m);
  f("glass_thickness_mm", s.glass_thickness_mm);
  f("glass_refractive_index", s.glass_refractive_index);
  f("attach", s.attach, OneOf{Attach::kLens, Attach::kWindow});
  f("drop_side", s.drop_side, OneOf{DropSide::kScene, DropSide::kCamera});
  f("glass_tilt_deg", s.glass_tilt_deg);
  f.custom(  // a window pose, or null on the lens
      "window", [&] { return s.window ? json_fields::write(*s.window, kWindowFields) : Json(nullptr); },
      [&](const JsonReader& r, const std::string& k) {
        if (r.has(k) && !r.value()[k].is_null())
          s.window = json_fields::read(r.child(k), WindowPose{}, kWindowFields, json_fields::Absent::kError);
        else
          r.mark(k);
      });
  f("refractive_index", s.refractive_index);
  f("slide_speed_mm_s", s.slide_speed_mm_s);
  f("slide_min_radius_mm", s.slide_min_radius_mm);
  f("samples_per_pixel", s.samples_per_pixel);
  f("max_bounces", s.max_bounces);
  f("geometry", s.geometry, OneOf{CapGeometry::kAnalytic, CapGeometry::kTriangles});
  f("cap_segments", s.cap_segments);
  f.custom(  // [r, g, b], or "mean" / "sky" for the view's mean or the sky
      "environment_radiance",
      [&] { return s.environment_radiance ? Json(*s.environment_radiance) : Json(s.environment_sky ? "sky" : "mean"); },
      [&](const JsonReader& r, const std::string& k) {
        if (r.has(k) && r.value()[k].is_string()) {
          const std::string v = r.get<std::string>(k);
          if (v != "mean" && v != "sky")
            throw InputError(r.where(k), "expected \"mean\", \"sky\" or [r, g, b], got \"" + v + "\"");
          s.environment_sky = v == "sky";
        } else if (r.has(k) && !r.value()[k].is_null()) {
          s.environment_radiance = r.get_array<3>(k);
        } else {
          r.mark(k);
        }
      });
  f.custom(  // [r, g, b], or "environment" for what the drops see around them
      "camera_radiance", [&] { return s.camera_radiance ? Json(*s.camera_radiance) : Json("environment"); },
      [&](const JsonReader& r, const std::string& k) {
        if (r.has(k) && r.value()[k].is_string()) {
          const std::string v = r.get<std::string>(k);
          if (v != "environment")
            throw InputError(r.where(k), "expected \"environment\" or [r, g, b], got \"" + v + "\"");
          s.camera_radiance.reset();
        } else if (r.has(k) && !r.value()[k].is_null()) {
          s.camera_radiance = r.get_array<3>(k);
        } else {
          r.mark(k);
        }
      });
  f("defocus", s.defocus);
  f("mask_rule", s.mask_rule, OneOf{LensMaskRule::kPerceptible, LensMaskRule::kCoverage});
  f("mask_min_change_levels", s.mask_min_change_levels, json_fields::Bounds{0, 255});
  f("mask_threshold", s.mask_threshold);
  f("sampling_margin", s.sampling_margin);
};

}  // namespace

LensDropletSpec parse_lens_droplet_spec(const JsonReader& r) {
  if (!r.is_object()) throw InputError(r.where(), "expected an object (the lens_droplets effect)");
  LensDropletSpec s = json_fields::read(r, LensDropletSpec{}, kLensFields, json_fields::Absent::kKeep);
  validate_lens_droplet_spec(s, r.where());
  return s;
}

void validate_lens_droplet_spec(const LensDropletSpec& s, const std::string& where) {
  auto fin = [](double v) { return std::isfinite(v); };
  require(s.count >= 0 && s.count <= 100000, where, "count", std::to_string(s.count), "0..100000");
  require(fin(s.radius_mm[0]) && fin(s.radius_mm[1]) && s.radius_mm[0] > 0 &&
              s.radius_mm[0] <= s.radius_mm[1] && s.radius_mm[1] <= 1000,
          where, "radius_mm", "[" + num(s.radius_mm[0]) + ", " + num(s.radius_mm[1]) + "]",
          "0 < min <= max <= 1000 mm");
  require(fin(s.contact_angle_deg[0]) && fin(s.contact_angle_deg[1]) && s.contact_angle_deg[0] > 0 &&
              s.contact_angle_deg[0] <= s.contact_angle_deg[1] && s.contact_angle_deg[1] < 180,
          where, "contact_angle_deg",
          "[" + num(s.contact_angle_deg[0]) + ", " + num(s.contact_angle_deg[1]) + "]",
          "0 < min <= max < 180 degrees");
  require(fin(s.glass_distance_m) && s.glass_distance_m > 1e-4 && s.glass_distance_m <= 100, where,
          "glass_distance_m", num(s.glass_distance_m), "0.0001 < value <= 100 m");
  require(fin(s.glass_thickness_mm) && s.glass_thickness_mm >= 0 && s.glass_thickness_mm <= 10, where,
          "glass_thickness_mm", num(s.glass_thickness_mm), "0 (thin glass) <= value <= 10 mm");
  require(s.glass_thickness_mm * 1e-3 < 0.5 * s.glass_distance_m, where, "glass_thickness_mm",
          num(s.glass_thickness_mm), "less than half of glass_distance_m (the slab lies between the camera and the drops)");
  require(fin(s.glass_refractive_index) && s.glass_refractive_index >= 1 && s.glass_refractive_index <= 2.5, where,
          "glass_refractive_index", num(s.glass_refractive_index), "1 <= value <= 2.5");
  require(fin(s.glass_tilt_deg[0]) && fin(s.glass_tilt_deg[1]) && std::abs(s.glass_tilt_deg[0]) < 80 &&
              std::abs(s.glass_tilt_deg[1]) < 80,
          where, "glass_tilt_deg", "[" + num(s.glass_tilt_deg[0]) + ", " + num(s.glass_tilt_deg[1]) + "]",
          "|tilt| < 80 degrees about each axis");
  if (s.attach == Attach::kWindow) {
    require(s.glass_tilt_deg[0] == 0 && s.glass_tilt_deg[1] == 0, where, "glass_tilt_deg", "a tilt",
            "no tilt with attach \"window\" (the window pose sets the orientation)");
  } else {
    require(!s.window, where, "window", "a window pose", "no window with attach \"lens\"");
  }
  if (s.window) {
    const WindowPose& w = *s.window;
    require(w.center_world.allFinite(), where, "window/center_world", "a non-finite value", "finite");
    require(w.normal_world.allFinite() && w.normal_world.norm() > 1e-9, where, "window/normal_world",
            "a zero or non-finite vector", "a non-zero direction");
    Eigen::Vector3d down = -w.up_world + w.up_world.dot(w.normal_world.normalized()) * w.normal_world.normalized();
    require(w.up_world.allFinite() && down.norm() > 1e-6 * std::max(1.0, w.up_world.norm()), where,
            "window/up_world", "a direction parallel to the normal (or zero)",
            "a direction not parallel to normal_world");
    require(fin(w.size_m[0]) && fin(w.size_m[1]) && w.size_m[0] > 0 && w.size_m[1] > 0 &&
                w.size_m[0] <= 1e4 && w.size_m[1] <= 1e4,
            where, "window/size_m", "[" + num(w.size_m[0]) + ", " + num(w.size_m[1]) + "]",
            "0 < width, height <= 10000 m");
  }
  require(fin(s.refractive_index) && s.refractive_index >= 1.0 && s.refractive_index <= 3.0, where,
          "refractive_index", num(s.refractive_index), "1 <= value <= 3");
  require(fin(s.slide_speed_mm_s) && s.slide_speed_mm_s >= 0 && s.slide_speed_mm_s <= 1e4, where,
          "slide_speed_mm_s", num(s.slide_speed_mm_s), "0 <= value <= 10000 mm/s");
  require(fin(s.slide_min_radius_mm) && s.slide_min_radius_mm >= 0, where, "slide_min_radius_mm",
          num(s.slide_min_radius_mm), ">= 0 mm");
  require(s.samples_per_pixel >= 1 && s.samples_per_pixel <= 4096, where, "samples_per_pixel",
          std::to_string(s.samples_per_pixel), "1..4096");
  require(s.max_bounces >= 0 && s.max_bounces <= 64, where, "max_bounces", std::to_string(s.max_bounces),
          "0..64");
  require(s.cap_segments >= 6 && s.cap_segments <= 1024, where, "cap_segments",
          std::to_string(s.cap_segments), "6..1024");
  if (s.camera_radiance)
    for (double v : *s.camera_radiance)
      require(fin(v) && v >= 0 && v <= 1e6, where, "camera_radiance", num(v), "0 <= value <= 1e6 (linear radiance)");
  if (s.environment_radiance)
    for (double v : *s.environment_radiance)
      require(fin(v) && v >= 0 && v <= 1e6, where, "environment_radiance", num(v),
              "finite linear radiance >= 0");
  require(fin(s.mask_threshold) && s.mask_threshold > 0 && s.mask_threshold <= 1, where, "mask_threshold",
          num(s.mask_threshold), "0 < value <= 1");
  require(fin(s.sampling_margin) && s.sampling_margin >= 0 && s.sampling_margin <= 10, where,
          "sampling_margin", num(s.sampling_margin), "0..10 (fraction of the visible glass per side)");
}

Json lens_droplet_spec_to_json(const LensDropletSpec& s) { return json_fields::write(s, kLensFields); }

}  // namespace weathergs::generator::lens
