#include "core/dataset.h"

#include <cstdio>
#include <filesystem>
#include <set>

#include "core/atomic_file.h"
#include "core/json_fields.h"

namespace weathergs {

namespace fs = std::filesystem;

const Camera& Dataset::camera(const std::string& view) const {
  for (const Camera& c : cameras)
    if (c.name == view) return c;
  throw InputError(file(layout::kCamerasJson), "no view named '" + view + "'");
}

const std::vector<std::string>& Dataset::split(const std::string& name) const {
  auto it = info.splits.find(name);
  if (it == info.splits.end())
    throw InputError(file(layout::kDatasetJson) + ":/splits", "no split named '" + name + "'");
  return it->second;
}

const char* folder_of(ImageKind kind) {
  switch (kind) {
    case ImageKind::kImages: return layout::kImagesDir;
    case ImageKind::kClean: return layout::kCleanDir;
    case ImageKind::kDepth: return layout::kDepthDir;
    case ImageKind::kLensMask: return layout::kLensMaskDir;
    case ImageKind::kParticleMask: return layout::kParticleMaskDir;
    case ImageKind::kTargetNoParticles: return layout::kTargetNoParticlesDir;
    case ImageKind::kTargetLensOnly: return layout::kTargetLensOnlyDir;
  }
  WGS_CHECK(false);
}

const char* extension_of(ImageKind kind) { return kind == ImageKind::kDepth ? layout::kDepthExt : layout::kImageExt; }

const char* to_string(ImageKind kind) {
  switch (kind) {
    case ImageKind::kImages: return "images";
    case ImageKind::kClean: return "clean";
    case ImageKind::kDepth: return "depth";
    case ImageKind::kLensMask: return "lens_mask";
    case ImageKind::kParticleMask: return "particle_mask";
    case ImageKind::kTargetNoParticles: return "target_no_particles";
    case ImageKind::kTargetLensOnly: return "target_lens_only";
  }
  WGS_CHECK(false);
}

std::string Dataset::path(ImageKind kind, const std::string& view) const {
  return (fs::path(root) / folder_of(kind) / (view + extension_of(kind))).string();
}

std::string Dataset::dir(ImageKind kind) const { return (fs::path(root) / folder_of(kind)).string(); }

std::string Dataset::layer_path(const std::string& name, const std::string& view, const std::string& ext) const {
  return (fs::path(root) / layout::kLayersDir / name / (view + ext)).string();
}

std::string Dataset::file(const std::string& relative) const { return (fs::path(root) / relative).string(); }

bool Dataset::has(ImageKind kind) const { return fs::is_directory(dir(kind)); }

std::string Dataset::clean_or_input_path(const std::string& view) const {
  return path(has(ImageKind::kClean) ? ImageKind::kClean : ImageKind::kImages, view);
}

std::map<std::string, std::vector<std::string>> llff_splits(const std::vector<std::string>& views, int every) {
  std::map<std::string, std::vector<std::string>> s{{"train", {}}, {"test", {}}};
  for (size_t i = 0; i < views.size(); ++i) s[i % size_t(every) == 0 ? "test" : "train"].push_back(views[i]);
  return s;
}

std::string numbered_view_name(int index, int digits) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%0*d", digits, index);
  return buf;
}

bool is_safe_view_name(const std::string& name) {
  if (name.empty() || name[0] == '.') return false;
  for (char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '_' || c == '-')) return false;
  return true;
}

namespace {
Eigen::Matrix4d read_matrix4(const JsonReader& r) {
  if (!r.is_array() || r.size() != 4) throw InputError(r.where(), "expected a 4x4 array of rows");
  Eigen::Matrix4d m;
  for (size_t i = 0; i < 4; ++i) {
    JsonReader row = r.at(i);
    if (!row.is_array() || row.size() != 4) throw InputError(row.where(), "expected a row of 4 numbers");
    for (size_t j = 0; j < 4; ++j) m(int(i), int(j)) = row.at(j).as<double>();
  }
  return m;
}
}  // namespace

namespace {
// One view of cameras.json (DATASET_FORMAT.md): the intrinsics and pose are required, the shutter
// defaults to an instant at 0, and the lens keys are written only when known.
constexpr auto kCameraFields = [](auto& c, auto& f) {
  f("name", c.name);
  f("width", c.width);
  f("height", c.height);
  f("fx", c.fx);
  f("fy", c.fy);
  f("cx", c.cx);
  f("cy", c.cy);
  f.custom(
      "camera_from_world",
      [&] {
        Json m = Json::array();
        for (int i = 0; i < 4; ++i) m.push_back({c.camera_from_world(i, 0), c.camera_from_world(i, 1),
                                                 c.camera_from_world(i, 2), c.camera_from_world(i, 3)});
        return m;
      },
      [&](const JsonReader& r, const std::string& k) { c.camera_from_world = read_matrix4(r.child(k)); });
  f("time_s", c.time_s, json_fields::Optional{});
  f("exposure_s", c.exposure_s, json_fields::Optional{});
  f("f_number", c.f_number);
  f("focal_length_mm", c.focal_length_mm);
  f("focus_distance_m", c.focus_distance_m);
};
}  // namespace

Camera camera_from_json(const JsonReader& r) {
  if (!r.is_object()) throw InputError(r.where(), "expected a camera object");
  const Camera c = json_fields::read(r, Camera{}, kCameraFields, json_fields::Absent::kError);
  if (!is_safe_view_name(c.name))
    throw InputError(r.where("name"), "view name '" + c.name + "' is not file-system safe ([A-Za-z0-9._-])");
  validate_camera(c, r.where());
  return c;
}

Json camera_to_json(const Camera& c) { return json_fields::write(c, kCameraFields); }

std::vector<Camera> read_cameras_json(const std::string& path) {
  JsonReader root = JsonReader::from_file(path);
  if (!root.is_object()) throw InputError(root.where(), "expected an object with key 'views'");
  JsonReader views = root.child("views");
  root.finish();
  if (!views.is_array()) throw InputError(views.where(), "expected an array of cameras");
  std::vector<Camera> cams;
  std::set<std::string> names;
  for (size_t i = 0; i < views.size(); ++i) {
    cams.push_back(camera_from_json(views.at(i)));
    if (!names.insert(cams.back().name).second)
      throw InputError(views.at(i).where("name"), "duplicate view name '" + cams.back().name + "'");
  }
  if (cams.empty()) throw InputError(views.where(), "expected at least one camera");
  return cams;
}

namespace {
// dataset.json after its format header (DATASET_FORMAT.md). generator/ and imported footage own what
// their blocks hold; here they pass through whole.
constexpr auto kDatasetFields = [](auto& d, auto& f) {
  f("name", d.name);
  f("scene", d.scene, json_fields::WhenAbsent{std::string()});
  f("weather", d.weather, json_fields::WhenAbsent{std::string("clear")});
  f.custom(
      "splits", [&] { return Json(d.splits); },
      [&](const JsonReader& r, const std::string& k) {
        const JsonReader splits = r.child(k);
        if (!splits.is_object()) throw InputError(splits.where(), "expected an object of named view lists");
        for (const std::string& key : splits.keys()) {
          const JsonReader list = splits.child(key);
          if (!list.is_array()) throw InputError(list.where(), "expected an array of view names");
          std::vector<std::string>& views = d.splits[key];
          for (size_t i = 0; i < list.size(); ++i) views.push_back(list.at(i).template as<std::string>());
        }
      });
  f("splits_rule", d.splits_rule);
  f.custom(
      "generator", [&] { return d.generator ? *d.generator : Json(Json::value_t::discarded); },
      [&](const JsonReader& r, const std::string& k) {
        if (!r.has(k)) return r.mark(k);
        const JsonReader g = r.child(k);
        if (!g.is_object()) throw InputError(g.where(), "expected an object");
        d.generator = g.value();
      });
  f.custom(
      "source", [&] { return d.source ? *d.source : Json(Json::value_t::discarded); },
      [&](const JsonReader& r, const std::string& k) {
        if (!r.has(k)) return r.mark(k);
        d.source = r.child(k).value();
      });
  f.custom(
      "identity", [&] { return d.identity ? *d.identity : Json(Json::value_t::discarded); },
      [&](const JsonReader& r, const std::string& k) {
        if (!r.has(k)) return r.mark(k);
        const JsonReader g = r.child(k);
        if (!g.is_object()) throw InputError(g.where(), "expected an object {scheme, sha256, file_count, files}");
        d.identity = g.value();
      });
};
}  // namespace

DatasetInfo read_dataset_json(const std::string& path) {
  JsonReader r = JsonReader::from_file(path);
  if (!r.is_object()) throw InputError(r.where(), "expected an object");
  const std::string format = r.get<std::string>("format");
  if (format != "weathergs-dataset")
    throw InputError(r.where("format"), "expected \"weathergs-dataset\", got \"" + format + "\"");
  const int version = r.get<int>("version");
  if (version != 1) throw InputError(r.where("version"), "unsupported version " + std::to_string(version) + " (expected 1)");
  return json_fields::read(r, DatasetInfo{}, kDatasetFields, json_fields::Absent::kError);
}

Json dataset_info_to_json(const DatasetInfo& info) {
  Json j = json_fields::write(info, kDatasetFields);
  j["format"] = "weathergs-dataset";
  j["version"] = 1;
  return j;
}

void validate_dataset(const Dataset& d, const std::string& where) {
  std::set<std::string> names;
  for (const Camera& c : d.cameras)
    if (!names.insert(c.name).second) throw InputError(where, "duplicate view name '" + c.name + "'");
  for (const auto& [split, views] : d.info.splits)
    for (const std::string& v : views)
      if (!names.count(v))
        throw InputError(where + ":/splits/" + split, "view '" + v + "' is not in cameras.json");
  auto train = d.info.splits.find("train"), test = d.info.splits.find("test");
  if (train != d.info.splits.end() && test != d.info.splits.end()) {
    std::set<std::string> t(test->second.begin(), test->second.end());
    for (const std::string& v : train->second)
      if (t.count(v)) throw InputError(where + ":/splits", "view '" + v + "' is in both train and test");
  }
}

Dataset read_dataset(const std::string& root) {
  if (!fs::is_directory(root)) throw InputError(root, "dataset directory does not exist");
  Dataset d;
  d.root = root;
  d.info = read_dataset_json((fs::path(root) / layout::kDatasetJson).string());
  d.cameras = read_cameras_json((fs::path(root) / layout::kCamerasJson).string());
  validate_dataset(d, (fs::path(root) / layout::kDatasetJson).string());
  return d;
}

void write_cameras_json(const std::string& path, const std::vector<Camera>& cameras) {
  Json views = Json::array();
  for (const Camera& c : cameras) views.push_back(camera_to_json(c));
  write_file_atomic(path, Json{{"views", views}}.dump(2) + "\n");
}

void write_dataset_json(const std::string& path, const DatasetInfo& info) {
  write_file_atomic(path, dataset_info_to_json(info).dump(2) + "\n");
}

void write_dataset(const Dataset& d) {
  validate_dataset(d, d.root);
  write_cameras_json((fs::path(d.root) / layout::kCamerasJson).string(), d.cameras);
  write_dataset_json((fs::path(d.root) / layout::kDatasetJson).string(), d.info);
}

}  // namespace weathergs
