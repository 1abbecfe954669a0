#include "capture/generate.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/dataset_identity.h"
#include "core/version.h"
#include "core/error.h"
#include "core/file_lock.h"
#include "core/progress.h"
#include "core/sha256.h"
#include "capture/exports.h"
#include "capture/process.h"
#include "generator/weather.h"

namespace weathergs::capture {

namespace fs = std::filesystem;

namespace {

Json stats_json(const ModelStats& s) {
  return {{"registered_images", s.registered_images}, {"points", s.points}, {"observations", s.observations},
          {"mean_track_length", s.mean_track_length}, {"mean_reprojection_error_px", s.mean_reprojection_error_px}};
}

// Bumped whenever the meaning of a cached render changes without the job or the scripts changing.
constexpr const char* kCacheVersion = "weathergs-clean-cache-v3";

std::string cache_key(const SceneSpec& scene, const std::string& variant, const GenerateOptions& o) {
  const VariantSpec v = scene.variant(variant);
  const ProfileSpec& p = scene.profile(o.profile);
  std::vector<Camera> cams = scene_cameras(scene, p);
  if (o.blender.max_views > 0 && int(cams.size()) > o.blender.max_views) cams.resize(size_t(o.blender.max_views));
  Json job = blender_job(scene, v, p, cams, {});
  job.erase("scene_file");  // the same spec at another path renders the same images
  Sha256 h;
  h.update(std::string(kCacheVersion) + "\n");
  h.update(job.dump() + "\n");
  // The script and every module of its package: a change in any of them is a new render.
  const fs::path scripts = fs::path(o.blender.script).parent_path();
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(scripts))
    if (e.is_regular_file() && e.path().extension() == ".py") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  for (const fs::path& f : files) {
    h.update(fs::relative(f, scripts).generic_string() + "\n");
    h.update(read_file(f.string()));
  }
  h.update(std::string("colmap_oracle=") + (o.colmap ? "1" : "0"));
  return h.hex_digest().substr(0, 24);
}

// The tools that made the dataset at root: Blender's version from its render log, COLMAP's by asking.
ToolVersions tools_of(const std::string& cache_entry, const GenerateOptions& o) {
  ToolVersions t;
  const fs::path log = fs::path(cache_entry) / layout::kLogsDir / "render_log.json";
  if (fs::exists(log)) t.blender = Json::parse(read_file(log.string())).value("blender", "");
  if (o.colmap) t.colmap = colmap_version(o.colmap_options.executable);
  return t;
}

// Settings equal but for the restoration targets: those add targets/ and change nothing else, so
// such datasets are compared on the files both have.
bool same_but_targets(GenerationSettings a, GenerationSettings b) {
  a.targets = b.targets = false;
  return a == b;
}

DatasetIdentity without_targets(const DatasetIdentity& id) {
  std::map<std::string, std::string> files;
  for (const auto& [path, sha] : id.files)
    if (path.rfind("targets/", 0) != 0) files[path] = sha;
  return identity_of_files(std::move(files));
}

// The two identities over the files both datasets have (the targets only when both made them).
std::pair<DatasetIdentity, DatasetIdentity> comparable(const DatasetIdentity& found, const GenerationSettings& fs,
                                                       const DatasetIdentity& want, const GenerationSettings& ws) {
  if (fs.targets == ws.targets) return {found, want};
  return {fs.targets ? without_targets(found) : found, ws.targets ? without_targets(want) : want};
}

// Records the dataset's identity and holds it against the expected one (GenerateOptions). Writes
// dataset.json's identity and generator.identity_check; throws InputError on a mismatch unless allowed.
void check_identity(const SceneSpec& scene, const std::string& variant, const GenerateOptions& o,
                    const std::string& root, GenerateSummary& s) {
  const DatasetIdentity id = record_dataset_identity(root);
  s.identity = id.sha256;
  const std::string name = scene.name + "_" + variant;
  const std::string path = expected_identities_path(scene.file, o.profile);
  DatasetInfo info = read_dataset_json((fs::path(root) / layout::kDatasetJson).string());
  GenerationSettings settings;
  settings.weather_spec = info.generator && info.generator->contains("spec") ? info.generator->at("spec") : Json();
  settings.max_views = o.blender.max_views;
  settings.targets = o.targets;
  settings.colmap = o.colmap;
  const ToolVersions found = tools_of(s.cache_entry, o);
  Json check = {{"expected_file", path}, {"tools", found.to_json()}};
  if (o.record_expected) {
    write_expected_identity(path, o.profile, {name, settings, found, source_commit(), id});
    s.identity_check = "recorded";
  } else if (const std::optional<ExpectedIdentity> want = read_expected_identity(path, name); !want) {
    s.identity_check = "no expected identity";
  } else if (!same_but_targets(want->settings, settings)) {
    s.identity_check = "not checked: other settings than the expected identity's";
  } else if (const auto [found_id, want_id] = comparable(id, settings, want->identity, want->settings);
             want_id.sha256 == found_id.sha256) {
    s.identity_check = "matches";
  } else {
    const std::string first = first_difference(found_id, want_id).value_or("?");
    check["expected"] = want->identity.sha256;
    check["first_difference"] = first;
    // A render that differs is kept in the cache and would be reused by every later run: say where it is.
    const bool render = first.rfind("clean/", 0) == 0 || first.rfind("depth/", 0) == 0;
    if (!o.allow_identity_mismatch)
      throw InputError(path, name + " (" + o.profile + " profile) is not the benchmark's dataset: identity " +
                                 id.sha256.substr(0, 12) + " where " + want->identity.sha256.substr(0, 12) +
                                 " is expected; first difference: " + first + ". Expected made with " +
                                 describe(want->made_with) + " (weathergs " + want->weathergs_commit + "), found " +
                                 describe(found) + "." +
                                 (render ? " The clean render comes from the cache entry " + s.cache_entry +
                                               ", which later runs reuse; Cycles can round a pixel one level "
                                               "differently in another process (docs/determinism.md): remove that "
                                               "folder to render the variant again."
                                         : "") +
                                 " Pass --allow-identity-mismatch to keep this dataset anyway (its dataset.json says so)");
    s.identity_check = "mismatch allowed";
  }
  check["result"] = s.identity_check;
  Json gen = info.generator ? *info.generator : Json::object();
  gen["identity_check"] = check;
  info.generator = gen;
  write_dataset_json((fs::path(root) / layout::kDatasetJson).string(), info);
}

}  // namespace

Json GenerateSummary::to_json() const {
  return {{"scene", scene}, {"variant", variant}, {"out_dir", out_dir}, {"cache_entry", cache_entry},
          {"cache_hit", cache_hit}, {"views", views}, {"render_seconds", render_s}, {"weather_seconds", weather_s},
          {"colmap_seconds", colmap_s}, {"total_seconds", total_s}, {"sparse", stats_json(sparse)},
          {"sparse_clean", stats_json(sparse_clean)}, {"identity", identity}, {"identity_check", identity_check}};
}

void GenerateOptions::validate() const {
  if (profile.empty()) throw InputError("generate options", "profile is empty");
  if (cache_dir.empty()) throw InputError("generate options", "cache_dir is empty: a cache folder for clean renders is required");
  blender.validate();
  colmap_options.validate();
}

std::string ensure_clean_render(const SceneSpec& scene, const std::string& variant, const GenerateOptions& o,
                                bool* cache_hit, double* seconds) {
  const auto start = std::chrono::steady_clock::now();
  o.validate();
  const fs::path root = fs::path(o.cache_dir) / "clean";
  fs::create_directories(root);
  const fs::path entry = root / (scene.name + "_" + variant + "_" + o.profile + "_" + cache_key(scene, variant, o));
  // Entries appear atomically (AtomicDirectory), so an existing one is complete.
  auto hit = [&] {
    if (!fs::exists(entry / layout::kDatasetJson)) return false;
    if (cache_hit) *cache_hit = true;
    if (seconds) *seconds = seconds_since(start);
    return true;
  };
  if (hit()) return entry.string();
  // A render is needed: Blender must be there before the lock is taken and any work starts.
  if (find_executable(o.blender.executable).empty())
    throw InputError(o.blender.executable, "Blender not found (is it installed? scripts/install-deps.sh installs it; "
                                           "--blender PATH names another)");
  // One renderer per entry: concurrent generate runs (threads, processes, cluster jobs on a shared
  // file system) wait for the first one and then reuse its render.
  // Lock files live beside clean/, not in it: clean/ holds complete entries only.
  const fs::path locks = fs::path(o.cache_dir) / "locks";
  fs::create_directories(locks);
  const std::string lock_path = (locks / (entry.filename().string() + ".lock")).string();
  FileLock lock(lock_path, [&] {
    std::fprintf(stderr, "waiting for another process rendering %s (lock %s)\n", entry.string().c_str(),
                 lock_path.c_str());
  });
  if (hit()) return entry.string();
  AtomicDirectory dir(entry.string());
  // render_clean_dataset is atomic itself: it replaces the (empty) staging directory on success.
  render_clean_dataset(scene, variant, o.profile, dir.path(), o.blender);
  if (o.colmap) {
    const Dataset ds = read_dataset(dir.path());
    triangulate_known_poses(ds.cameras, ds.dir(ImageKind::kClean), ds.file(std::string(layout::kLogsDir) + "/colmap_clean"),
                            ds.file(layout::kSparseCleanModelDir), o.colmap_options);
  }
  dir.commit();
  if (cache_hit) *cache_hit = false;
  if (seconds) *seconds = seconds_since(start);
  return entry.string();
}

GenerateSummary generate_variant(const std::string& scene_path, const std::string& variant_name,
                                 const std::string& out_dir, const GenerateOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  o.validate();
  const SceneSpec scene = read_scene_spec(scene_path);
  const VariantSpec variant = scene.variant(variant_name);
  scene.profile(o.profile);  // fail on a bad profile before rendering
  const bool has_weather = variant.weather.is_object();
  if (o.colmap && find_executable(o.colmap_options.executable).empty())
    throw InputError(o.colmap_options.executable, "COLMAP not found (is it installed? scripts/install-deps.sh installs "
                                                  "it; --colmap PATH names another, --no-colmap skips the SfM exports)");

  // Created first so that a bad --out fails before a long render.
  AtomicDirectory out(out_dir);
  GenerateSummary s;
  s.scene = scene.name;
  s.variant = variant.name;
  s.out_dir = out_dir;
  s.cache_entry = ensure_clean_render(scene, variant.name, o, &s.cache_hit, &s.render_s);

  const fs::path root(out.path());
  const std::string name = scene.name + "_" + variant.name;
  auto t = std::chrono::steady_clock::now();
  if (has_weather) {
    generator::WeatherRunOptions wopts;
    wopts.seed = o.seed;
    wopts.name = name;
    wopts.copy_exports = false;
    wopts.write_targets = o.targets;
    wopts.style = o.style;  // sparse/0 and transforms.json are made below from the weathered images
    // The particles are lit by the scene's sun (docs/record/generator_history.md, "Photometry"): the spec says so
    // unless it names its own lighting.
    Json weather = variant.weather;
    const Json& sun = variant.lights.at("sun");
    if (!weather.contains("lighting") && sun.at("strength").get<double>() > 0) {
      Json irradiance = Json::array();
      for (int c = 0; c < 3; ++c) irradiance.push_back(sun.at("strength").get<double>() * sun.at("color")[c].get<double>());
      weather["lighting"] = {{"sun", {{"elevation_deg", sun.at("elevation_deg")},
                                      {"azimuth_deg", sun.at("azimuth_deg")},
                                      {"irradiance", irradiance}}}};
    }
    const JsonReader spec(weather, scene.file, "/variants/" + variant.name + "/weather");
    generator::run_weather(s.cache_entry, spec, root.string(), wopts);
  } else {
    for (ImageKind k : {ImageKind::kClean, ImageKind::kImages, ImageKind::kDepth})
      copy_tree((fs::path(s.cache_entry) / folder_of(k)).string(), (root / folder_of(k)).string());
    for (const char* f : {layout::kCamerasJson, layout::kDatasetJson}) fs::copy_file(fs::path(s.cache_entry) / f, root / f);
  }
  s.weather_s = seconds_since(t);

  Dataset ds = read_dataset(root.string());
  s.views = int(ds.cameras.size());
  t = std::chrono::steady_clock::now();
  if (o.colmap) {
    // What a method would really get: features of the weather images, with the known poses.
    const std::string logs = ds.file(std::string(layout::kLogsDir) + "/colmap");
    TriangulationResult tri = triangulate_known_poses(ds.cameras, ds.dir(ImageKind::kImages), logs,
                                                      ds.file(layout::kSparseModelDir), o.colmap_options);
    s.sparse = tri.stats;
    // The oracle: the same from the clean images (cached with the render).
    copy_tree((fs::path(s.cache_entry) / layout::kSparseCleanModelDir).string(), ds.file(layout::kSparseCleanModelDir));
    s.sparse_clean = analyze_model(ds.file(layout::kSparseCleanModelDir), o.colmap_options, logs + "/colmap.log");
  }
  s.colmap_s = seconds_since(t);
  write_transforms_json(ds.file(layout::kTransformsJson), ds.cameras);

  // dataset.json, one straight line: the render (cached) wrote its entries, the weather added its
  // own; generate adds only what it did itself (which cache entry, the COLMAP stage).
  ds.info.name = name;
  ds.info.scene = scene.name;
  ds.info.weather = variant.name;
  Json gen = ds.info.generator ? *ds.info.generator : Json::object();
  if (!gen.contains("stages") || !gen["stages"].is_array()) gen["stages"] = Json::array();
  if (o.colmap) gen["stages"].push_back({{"name", "colmap"}, {"seconds", s.colmap_s}});
  gen["scene_spec"] = scene.file;
  gen["clean_render"] = {{"entry", fs::path(s.cache_entry).filename().string()},
                         {"cached", s.cache_hit},
                         {"seconds", s.render_s}};
  if (o.colmap) gen["colmap"] = {{"sparse", stats_json(s.sparse)}, {"sparse_clean", stats_json(s.sparse_clean)}};
  ds.info.generator = gen;
  write_dataset_json(ds.file(layout::kDatasetJson), ds.info);
  check_identity(scene, variant.name, o, root.string(), s);
  out.commit();
  s.total_s = seconds_since(start);
  return s;
}

std::vector<GenerateSummary> generate_suite(const std::string& suite_path, const std::string& out_dir,
                                            const GenerateOptions& o) {
  JsonReader r = JsonReader::from_file(suite_path);
  if (!r.is_object()) throw InputError(r.where(), "expected a suite object {name, variants}");
  const std::string suite_name = r.get<std::string>("name");
  r.get_or<std::string>("description", "");
  // A suite may fix the weather style of all its variants (scenes/suite_physical.json); an explicit
  // option wins.
  GenerateOptions vo = o;
  if (r.has("style")) {
    const generator::WeatherStyle style = r.get_enum("style", {generator::WeatherStyle::kPhysical, generator::WeatherStyle::kPaper});
    if (!vo.style) vo.style = style;
  }
  JsonReader list = r.child("variants");
  if (!list.is_array() || list.size() == 0) throw InputError(list.where(), "expected a non-empty array of variants");
  struct Item {
    std::string scene, weather;
  };
  std::vector<Item> items;
  const fs::path base = fs::path(suite_path).parent_path();
  for (size_t i = 0; i < list.size(); ++i) {
    JsonReader v = list.at(i);
    if (!v.is_object()) throw InputError(v.where(), "expected {\"scene\": \"pool.json\", \"weather\": \"rain\"}");
    Item it{(base / v.get<std::string>("scene")).string(), v.get<std::string>("weather")};
    v.finish();
    // Validate every variant before the first (slow) render.
    const SceneSpec spec = read_scene_spec(it.scene);
    spec.variant(it.weather);
    spec.profile(vo.profile);
    items.push_back(it);
  }
  r.finish();

  fs::create_directories(out_dir);
  std::vector<GenerateSummary> summaries;
  ProgressBar bar("generate " + suite_name, int64_t(items.size()));
  const auto start = std::chrono::steady_clock::now();
  for (const Item& it : items) {
    const SceneSpec spec = read_scene_spec(it.scene);
    bar.set_status(spec.name + "_" + it.weather);
    summaries.push_back(generate_variant(it.scene, it.weather, (fs::path(out_dir) / (spec.name + "_" + it.weather)).string(), vo));
    bar.tick();
  }
  bar.finish();
  Json all = Json::array();
  for (const auto& s : summaries) all.push_back(s.to_json());
  write_file_atomic((fs::path(out_dir) / "summary.json").string(),
                    Json{{"suite", suite_name}, {"profile", vo.profile},
                         {"style", vo.style ? to_string(*vo.style) : "per variant"},
                         {"total_seconds", seconds_since(start)},
                         {"variants", all}}
                        .dump(1));
  return summaries;
}

}  // namespace weathergs::capture
