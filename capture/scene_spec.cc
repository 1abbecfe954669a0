#include "capture/scene_spec.h"

#include <iterator>

#include <cmath>
#include <filesystem>
#include <limits>
#include <sstream>

#include "core/constants.h"
#include "core/dataset.h"
#include "core/error.h"
#include "capture/scene_types.h"

namespace weathergs::capture {

namespace fs = std::filesystem;

const std::vector<std::string>& scene_types() {
  static const std::vector<std::string> types(std::begin(generated::kSceneTypes), std::end(generated::kSceneTypes));
  return types;
}

namespace {

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

void check_camera_separation(const SceneSpec& scene, const ProfileSpec& profile, const std::string& where) {
  const std::vector<Camera> cams = scene_cameras(scene, profile);
  const double f = min_camera_separation_fraction(cams);
  if (f < kMinCameraSeparationFraction)
    throw InputError(where, "the camera path gives views closer than " + std::to_string(kMinCameraSeparationFraction) +
                                " of the path size (closest pair at " + std::to_string(f) +
                                "): raise camera.depth_m or radius_m, or change turns");
}

double read_number(const JsonReader& r, const std::string& key, double lo, double hi, const double* fallback) {
  return fallback ? r.get_number_or(key, *fallback, lo, hi) : r.get_number(key, lo, hi);
}

// An array of n (2 or 3) numbers in [lo, hi], as JSON; required unless a fallback is given.
Json read_vec(const JsonReader& r, const std::string& key, size_t n, double lo, double hi, const Json* fallback) {
  if (!r.has(key)) {
    if (!fallback) r.fail(key, "a required array of " + std::to_string(n) + " numbers");
    r.mark(key);
    return *fallback;
  }
  Json out = Json::array();
  if (n == 2) {
    for (double v : r.get_array<2>(key, lo, hi)) out.push_back(v);
  } else {
    WGS_CHECK_EQ(n, size_t(3));
    for (double v : r.get_array<3>(key, lo, hi)) out.push_back(v);
  }
  return out;
}

Eigen::Vector3d to_vec3(const Json& j) { return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; }

// Lights: {"sun": {strength, color, elevation_deg, azimuth_deg, angle_deg}, "sky": {horizon_color,
// zenith_color, strength}}. With `base`, every key is optional and defaults to base's value (variant
// overrides); without it all keys are required.
Json read_lights(const JsonReader& r, const Json* base) {
  if (!r.is_object()) throw InputError(r.where(), "expected an object with \"sun\" and \"sky\"");
  Json out = base ? *base : Json::object();
  auto num = [&](const JsonReader& o, const Json* b, const std::string& key, double lo, double hi) {
    const double fb = b ? (*b)[key].get<double>() : 0.0;
    return read_number(o, key, lo, hi, b ? &fb : nullptr);
  };
  auto vec = [&](const JsonReader& o, const Json* b, const std::string& key) {
    return read_vec(o, key, 3, 0.0, 100.0, b ? &(*b)[key] : nullptr);
  };
  if (!base || r.has("sun")) {
    JsonReader s = r.child("sun");
    if (!s.is_object()) throw InputError(s.where(), "expected an object");
    const Json* b = base ? &(*base)["sun"] : nullptr;
    out["sun"] = {{"strength", num(s, b, "strength", 0.0, 1000.0)},
                  {"color", vec(s, b, "color")},
                  {"elevation_deg", num(s, b, "elevation_deg", -90.0, 90.0)},
                  {"azimuth_deg", num(s, b, "azimuth_deg", -360.0, 360.0)},
                  {"angle_deg", num(s, b, "angle_deg", 0.0, 180.0)}};
    s.finish();
  }
  if (!base || r.has("sky")) {
    JsonReader s = r.child("sky");
    if (!s.is_object()) throw InputError(s.where(), "expected an object");
    const Json* b = base ? &(*base)["sky"] : nullptr;
    out["sky"] = {{"horizon_color", vec(s, b, "horizon_color")},
                  {"zenith_color", vec(s, b, "zenith_color")},
                  {"strength", num(s, b, "strength", 0.0, 1000.0)}};
    s.finish();
  }
  r.finish();
  return out;
}

Json read_surface(const JsonReader& r) {
  if (!r.is_object()) throw InputError(r.where(), "expected an object with \"kind\"");
  const std::string kind = r.get<std::string>("kind");
  Json out = {{"kind", kind}};
  if (kind == "snow") {
    const double coverage = 0.7, threshold = 0.5, scale = 1.5;
    const Json white = Json::array({0.8, 0.82, 0.85});
    out["coverage"] = read_number(r, "coverage", 0.0, 1.0, &coverage);
    out["normal_threshold"] = read_number(r, "normal_threshold", -1.0, 0.75, &threshold);
    out["noise_scale_m"] = read_number(r, "noise_scale_m", 1e-3, 1e3, &scale);
    out["color"] = read_vec(r, "color", 3, 0.0, 1.0, &white);
  } else if (kind == "rain") {
    const double wetness = 0.8, darkening = 0.5, puddles = 0.3, scale = 2.0;
    out["wetness"] = read_number(r, "wetness", 0.0, 1.0, &wetness);
    out["darkening"] = read_number(r, "darkening", 0.0, 1.0, &darkening);
    out["puddle_coverage"] = read_number(r, "puddle_coverage", 0.0, 1.0, &puddles);
    out["puddle_scale_m"] = read_number(r, "puddle_scale_m", 1e-3, 1e3, &scale);
  } else if (kind != "clear") {
    throw InputError(r.where("kind"), "expected \"snow\", \"rain\" or \"clear\", got \"" + kind + "\"");
  }
  r.finish();
  return out;
}

ProfileSpec read_profile(const JsonReader& r, const std::string& name) {
  if (!r.is_object()) throw InputError(r.where(), "expected an object {width, height, views, samples}");
  ProfileSpec p;
  p.name = name;
  p.width = int(read_number(r, "width", 8, 16384, nullptr));
  p.height = int(read_number(r, "height", 8, 16384, nullptr));
  p.views = int(read_number(r, "views", 1, 10000, nullptr));
  p.samples = int(read_number(r, "samples", 1, 65536, nullptr));
  for (const char* k : {"width", "height", "views", "samples"}) r.get<int>(k);  // integers, not 2.5
  p.engine = r.get_or<std::string>("engine", "eevee");
  if (p.engine != "eevee" && p.engine != "cycles")
    throw InputError(r.where("engine"), "expected \"eevee\" or \"cycles\", got \"" + p.engine + "\"");
  if (p.width < p.height)
    throw InputError(r.where("width"), "expected width >= height (Blender's horizontal sensor fit), got " +
                                           std::to_string(p.width) + "x" + std::to_string(p.height));
  r.finish();
  return p;
}

CameraPathSpec read_camera_path(const JsonReader& r) {
  if (!r.is_object()) throw InputError(r.where(), "expected an object");
  CameraPathSpec c;
  c.position_m = to_vec3(read_vec(r, "position_m", 3, -1e5, 1e5, nullptr));
  c.look_at_m = to_vec3(read_vec(r, "look_at_m", 3, -1e5, 1e5, nullptr));
  const Json rdef = Json::array({c.radius_m.x(), c.radius_m.y()});
  Json rad = read_vec(r, "radius_m", 2, 0.0, 1e3, &rdef);
  c.radius_m = {rad[0].get<double>(), rad[1].get<double>()};
  c.depth_m = read_number(r, "depth_m", 0.0, 1e3, &c.depth_m);
  c.turns = read_number(r, "turns", 0.0, 100.0, &c.turns);
  c.focal_length_mm = read_number(r, "focal_length_mm", 1.0, 5000.0, &c.focal_length_mm);
  c.sensor_width_mm = read_number(r, "sensor_width_mm", 1.0, 500.0, &c.sensor_width_mm);
  c.exposure_s = read_number(r, "exposure_s", 0.0, 10.0, &c.exposure_s);
  c.frame_interval_s = read_number(r, "frame_interval_s", 0.0, 1e4, &c.frame_interval_s);
  // Real lens data (optional, both or neither): the views get f_number and focus_distance_m, so the
  // generator defocuses lens drops and near particles as this camera would (docs/scenes.md).
  if (r.has("f_number") != r.has("focus_distance_m"))
    throw InputError(r.where(), "give both f_number and focus_distance_m (a real lens), or neither (a pinhole)");
  if (r.has("f_number")) {
    c.f_number = r.get_number("f_number", 0.5, 64);
    c.focus_distance_m = r.get_number("focus_distance_m", 1e-3 * c.focal_length_mm * 1.01, 1e5);
  }
  r.finish();
  const Eigen::Vector3d forward = c.look_at_m - c.position_m;
  if (forward.norm() < 1e-6) throw InputError(r.where("look_at_m"), "must differ from position_m");
  if (forward.normalized().cross(Eigen::Vector3d::UnitZ()).norm() < 1e-3)
    throw InputError(r.where("look_at_m"), "the camera must not look straight up or down (+z is up)");
  return c;
}

}  // namespace

const ProfileSpec& SceneSpec::profile(const std::string& name) const {
  auto it = profiles.find(name);
  if (it == profiles.end()) {
    std::vector<std::string> names;
    for (const auto& [n, p] : profiles) names.push_back(n);
    throw InputError(file + ":/profiles", "no profile \"" + name + "\" (available: " + join(names) + ")");
  }
  return it->second;
}

VariantSpec SceneSpec::variant(const std::string& name) const {
  auto it = variants.find(name);
  if (it != variants.end()) return it->second;
  if (name == "clear") return {"clear", Json{{"kind", "clear"}}, lights, Json()};
  std::vector<std::string> names{"clear"};
  for (const auto& [n, v] : variants) names.push_back(n);
  throw InputError(file + ":/variants", "no variant \"" + name + "\" (available: " + join(names) + ")");
}

double min_camera_separation_fraction(const std::vector<Camera>& cameras) {
  double min_d = std::numeric_limits<double>::infinity(), max_d = 0;
  for (size_t i = 0; i < cameras.size(); ++i)
    for (size_t j = i + 1; j < cameras.size(); ++j) {
      const double d = (cameras[i].center_world() - cameras[j].center_world()).norm();
      min_d = std::min(min_d, d);
      max_d = std::max(max_d, d);
    }
  if (cameras.size() < 2) return 1.0;
  return max_d > 0 ? min_d / max_d : 0.0;
}

SceneSpec read_scene_spec(const std::string& path) {
  if (!fs::is_regular_file(path)) throw InputError(path, "scene spec not found (expected a JSON file)");
  JsonReader r = JsonReader::from_file(path);
  if (!r.is_object()) throw InputError(r.where(), "expected a scene spec object");
  SceneSpec s;
  s.file = path;
  s.name = r.get<std::string>("name");
  if (s.name.empty() || s.name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_-") != std::string::npos)
    throw InputError(r.where("name"), "expected a lowercase name of [a-z0-9_-], got \"" + s.name + "\"");
  s.type = r.get<std::string>("type");
  const auto& types = scene_types();
  if (std::find(types.begin(), types.end(), s.type) == types.end())
    throw InputError(r.where("type"), "unknown scene type \"" + s.type + "\" (expected one of " + join(types) + ")");
  s.description = r.get_or<std::string>("description", "");
  const int64_t seed = r.get<int64_t>("seed");
  if (seed < 0) throw InputError(r.where("seed"), "expected a non-negative integer");
  s.seed = uint64_t(seed);
  for (const char* key : {"layout", "materials"}) {
    JsonReader c = r.child(key);
    if (!c.is_object()) throw InputError(c.where(), "expected an object");
    (std::string(key) == "layout" ? s.layout : s.materials) = c.value();
  }
  if (s.materials.empty()) throw InputError(r.where("materials"), "expected at least one material");
  s.lights = read_lights(r.child("lights"), nullptr);
  s.camera = read_camera_path(r.child("camera"));

  JsonReader profiles = r.child("profiles");
  if (!profiles.is_object() || profiles.size() == 0)
    throw InputError(profiles.where(), "expected an object of named profiles (e.g. quick, paper)");
  for (const std::string& name : profiles.keys()) s.profiles[name] = read_profile(profiles.child(name), name);
  profiles.finish();

  if (r.has("split")) {
    JsonReader sp = r.child("split");
    if (!sp.is_object()) throw InputError(sp.where(), "expected {\"rule\": \"llff\", \"every\": 8}");
    const std::string rule = sp.get<std::string>("rule");
    if (rule != "llff") throw InputError(sp.where("rule"), "expected \"llff\", got \"" + rule + "\"");
    s.split_every = sp.get_or<int>("every", 8);
    if (s.split_every < 2) throw InputError(sp.where("every"), "expected an integer >= 2");
    sp.finish();
  }

  // Every profile's path must give distinct views (a view repeated in the test split tests nothing).
  for (const auto& [name, profile] : s.profiles) check_camera_separation(s, profile, profiles.where(name));

  JsonReader variants = r.child("variants");
  if (!variants.is_object()) throw InputError(variants.where(), "expected an object of named variants");
  for (const std::string& name : variants.keys()) {
    if (name == "clear") throw InputError(variants.where(name), "\"clear\" is built in and cannot be redefined");
    if (name.empty() || name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789+_-") != std::string::npos)
      throw InputError(variants.where(name), "expected a variant name of [a-z0-9+_-]");
    JsonReader v = variants.child(name);
    if (!v.is_object()) throw InputError(v.where(), "expected {surface, lights, weather}");
    VariantSpec vs;
    vs.name = name;
    vs.surface = read_surface(v.child("surface"));
    vs.lights = v.has("lights") ? read_lights(v.child("lights"), &s.lights) : s.lights;
    if (v.has("weather")) {
      JsonReader w = v.child("weather");
      if (!w.is_object()) throw InputError(w.where(), "expected a weather spec object (docs/formats.md)");
      vs.weather = w.value();
    }
    v.finish();
    s.variants[name] = vs;
  }
  variants.finish();
  r.finish();
  return s;
}

std::vector<Camera> scene_cameras(const SceneSpec& scene, const ProfileSpec& profile) {
  const CameraPathSpec& c = scene.camera;
  const Eigen::Vector3d forward = (c.look_at_m - c.position_m).normalized();
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d up = right.cross(forward);
  const double f_px = c.focal_length_mm / c.sensor_width_mm * profile.width;
  std::vector<Camera> cams;
  for (int k = 0; k < profile.views; ++k) {
    // An ellipse in the image plane traversed `turns` times while the camera dollies linearly from
    // -depth_m to +depth_m along the viewing direction: with turns >= 2 the loops never revisit a
    // pose (the dolly separates them), so no two views coincide, and every view (test views
    // included) has path neighbours on both sides (docs/scenes.md, "Camera path").
    const double theta = 2.0 * kPi * c.turns * k / profile.views;
    const double dolly = profile.views > 1 ? 2.0 * (k + 0.5) / profile.views - 1.0 : 0.0;
    const Eigen::Vector3d center = c.position_m + right * (c.radius_m.x() * std::cos(theta)) +
                                   up * (c.radius_m.y() * std::sin(theta)) + forward * (c.depth_m * dolly);
    // OpenCV axes: z toward the target, x right (horizontal), y down.
    const Eigen::Vector3d z = (c.look_at_m - center).normalized();
    const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d y = z.cross(x);
    Camera cam;
    cam.name = numbered_view_name(k);
    cam.width = profile.width;
    cam.height = profile.height;
    cam.fx = cam.fy = f_px;
    cam.cx = 0.5 * profile.width;
    cam.cy = 0.5 * profile.height;
    Eigen::Matrix3d rot;
    rot.row(0) = x;
    rot.row(1) = y;
    rot.row(2) = z;
    cam.camera_from_world.setIdentity();
    cam.camera_from_world.topLeftCorner<3, 3>() = rot;
    cam.camera_from_world.topRightCorner<3, 1>() = -rot * center;
    cam.time_s = k * c.frame_interval_s;
    cam.exposure_s = c.exposure_s;
    cam.focal_length_mm = c.focal_length_mm;
    cam.f_number = c.f_number;
    cam.focus_distance_m = c.focus_distance_m;
    cams.push_back(cam);
  }
  return cams;
}

}  // namespace weathergs::capture
