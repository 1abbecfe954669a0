#include "generator/lens/lens_spec.h"

#include <cmath>
#include <sstream>

namespace weathergs::generator::lens {

const char* to_string(Attach a) { return a == Attach::kLens ? "lens" : "window"; }
const char* to_string(DropSide s) { return s == DropSide::kScene ? "scene" : "camera"; }
const char* to_string(RadiusDistribution d) {
  return d == RadiusDistribution::kLogUniform ? "log_uniform" : "uniform";
}
const char* to_string(CapGeometry g) { return g == CapGeometry::kAnalytic ? "analytic" : "triangles"; }
const char* to_string(LensMaskRule r) { return r == LensMaskRule::kPerceptible ? "perceptible" : "coverage"; }

namespace {

Eigen::Vector3d to_vec(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

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

LensDropletSpec parse_lens_droplet_spec(const JsonReader& r) {
  if (!r.is_object()) throw InputError(r.where(), "expected an object (the lens_droplets effect)");
  LensDropletSpec s;
  s.count = r.get_or<int>("count", s.count);
  s.radius_mm = r.get_range_or("radius_mm", s.radius_mm);
  s.radius_distribution = r.get_enum_or("radius_distribution", s.radius_distribution,
                                    {RadiusDistribution::kLogUniform, RadiusDistribution::kUniform});
  s.contact_angle_deg = r.get_range_or("contact_angle_deg", s.contact_angle_deg);
  s.glass_distance_m = r.get_or<double>("glass_distance_m", s.glass_distance_m);
  s.glass_thickness_mm = r.get_or<double>("glass_thickness_mm", s.glass_thickness_mm);
  s.glass_refractive_index = r.get_or<double>("glass_refractive_index", s.glass_refractive_index);
  s.attach = r.get_enum_or("attach", s.attach, {Attach::kLens, Attach::kWindow});
  s.drop_side = r.get_enum_or("drop_side", s.drop_side, {DropSide::kScene, DropSide::kCamera});
  s.glass_tilt_deg = r.get_array_or<2>("glass_tilt_deg", s.glass_tilt_deg);
  if (r.has("window") && !r.value()["window"].is_null()) {
    JsonReader w = r.child("window");
    if (!w.is_object()) throw InputError(w.where(), "expected an object");
    WindowPose p;
    p.center_world = to_vec(w.get_array_or<3>("center_world", {0, 0, 0}));
    if (!w.has("center_world")) w.fail("center_world", "a required key");
    p.normal_world = to_vec(w.get_array_or<3>("normal_world", {0, 1, 0}));
    if (!w.has("normal_world")) w.fail("normal_world", "a required key");
    p.up_world = to_vec(w.get_array_or<3>("up_world", {0, 0, 1}));
    p.size_m = w.get_array_or<2>("size_m", p.size_m);
    if (!w.has("size_m")) w.fail("size_m", "a required key");
    w.finish();
    s.window = p;
  } else {
    r.mark("window");
  }
  s.refractive_index = r.get_or<double>("refractive_index", s.refractive_index);
  s.slide_speed_mm_s = r.get_or<double>("slide_speed_mm_s", s.slide_speed_mm_s);
  s.slide_min_radius_mm = r.get_or<double>("slide_min_radius_mm", s.slide_min_radius_mm);
  s.samples_per_pixel = r.get_or<int>("samples_per_pixel", s.samples_per_pixel);
  s.max_bounces = r.get_or<int>("max_bounces", s.max_bounces);
  s.geometry = r.get_enum_or("geometry", s.geometry, {CapGeometry::kAnalytic, CapGeometry::kTriangles});
  s.cap_segments = r.get_or<int>("cap_segments", s.cap_segments);
  if (r.has("environment_radiance") && r.value()["environment_radiance"].is_string()) {
    std::string v = r.get<std::string>("environment_radiance");
    if (v != "mean" && v != "sky")
      throw InputError(r.where("environment_radiance"), "expected \"mean\", \"sky\" or [r, g, b], got \"" + v + "\"");
    s.environment_sky = v == "sky";
  } else if (r.has("environment_radiance") && !r.value()["environment_radiance"].is_null()) {
    s.environment_radiance = r.get_array_or<3>("environment_radiance", {0, 0, 0});
  } else {
    r.mark("environment_radiance");
  }
  if (r.has("camera_radiance") && r.value()["camera_radiance"].is_string()) {
    if (r.get<std::string>("camera_radiance") != "environment")
      throw InputError(r.where("camera_radiance"), "expected \"environment\" or [r, g, b], got \"" +
                                                       r.get<std::string>("camera_radiance") + "\"");
    s.camera_radiance.reset();
  } else if (r.has("camera_radiance") && !r.value()["camera_radiance"].is_null()) {
    s.camera_radiance = r.get_array_or<3>("camera_radiance", {0, 0, 0});
  } else {
    r.mark("camera_radiance");
  }
  s.defocus = r.get_or<bool>("defocus", s.defocus);
  s.mask_rule = r.get_enum_or("mask_rule", s.mask_rule, {LensMaskRule::kPerceptible, LensMaskRule::kCoverage});
  s.mask_min_change_levels = r.get_number_or("mask_min_change_levels", s.mask_min_change_levels, 0, 255);
  s.mask_threshold = r.get_or<double>("mask_threshold", s.mask_threshold);
  s.sampling_margin = r.get_or<double>("sampling_margin", s.sampling_margin);
  r.finish();
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

Json lens_droplet_spec_to_json(const LensDropletSpec& s) {
  Json j;
  j["count"] = s.count;
  j["radius_mm"] = {s.radius_mm[0], s.radius_mm[1]};
  j["radius_distribution"] = to_string(s.radius_distribution);
  j["contact_angle_deg"] = {s.contact_angle_deg[0], s.contact_angle_deg[1]};
  j["glass_distance_m"] = s.glass_distance_m;
  j["glass_thickness_mm"] = s.glass_thickness_mm;
  j["glass_refractive_index"] = s.glass_refractive_index;
  j["attach"] = to_string(s.attach);
  j["drop_side"] = to_string(s.drop_side);
  j["glass_tilt_deg"] = {s.glass_tilt_deg[0], s.glass_tilt_deg[1]};
  if (s.window) {
    const WindowPose& w = *s.window;
    j["window"] = {{"center_world", {w.center_world.x(), w.center_world.y(), w.center_world.z()}},
                   {"normal_world", {w.normal_world.x(), w.normal_world.y(), w.normal_world.z()}},
                   {"up_world", {w.up_world.x(), w.up_world.y(), w.up_world.z()}},
                   {"size_m", {w.size_m[0], w.size_m[1]}}};
  } else {
    j["window"] = nullptr;
  }
  j["refractive_index"] = s.refractive_index;
  j["slide_speed_mm_s"] = s.slide_speed_mm_s;
  j["slide_min_radius_mm"] = s.slide_min_radius_mm;
  j["samples_per_pixel"] = s.samples_per_pixel;
  j["max_bounces"] = s.max_bounces;
  j["geometry"] = to_string(s.geometry);
  j["cap_segments"] = s.cap_segments;
  if (s.environment_radiance)
    j["environment_radiance"] = {(*s.environment_radiance)[0], (*s.environment_radiance)[1],
                                 (*s.environment_radiance)[2]};
  else
    j["environment_radiance"] = s.environment_sky ? "sky" : "mean";
  if (s.camera_radiance)
    j["camera_radiance"] = {(*s.camera_radiance)[0], (*s.camera_radiance)[1], (*s.camera_radiance)[2]};
  else
    j["camera_radiance"] = "environment";
  j["defocus"] = s.defocus;
  j["mask_rule"] = to_string(s.mask_rule);
  j["mask_min_change_levels"] = s.mask_min_change_levels;
  j["mask_threshold"] = s.mask_threshold;
  j["sampling_margin"] = s.sampling_margin;
  return j;
}

}  // namespace weathergs::generator::lens
