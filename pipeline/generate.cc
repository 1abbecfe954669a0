#include "pipeline/generate.h"

#include <chrono>
#include <cstdlib>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/error.h"
#include "core/progress.h"
#include "core/sha256.h"
#include "pipeline/exports.h"

#if __has_include("generator/weather.h")
#include "generator/weather.h"
#define WEATHERGS_HAVE_WEATHER 1
#else
#define WEATHERGS_HAVE_WEATHER 0
#endif

namespace weathergs::pipeline {

namespace fs = std::filesystem;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

Json stats_json(const ModelStats& s) {
  return {{"registered_images", s.registered_images}, {"points", s.points}, {"observations", s.observations},
          {"mean_track_length", s.mean_track_length}, {"mean_reprojection_error_px", s.mean_reprojection_error_px}};
}

// Bumped whenever the meaning of a cached render changes without the job or the script changing.
constexpr const char* kCacheVersion = "weathergs-clean-cache-v2";

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
  h.update(read_file(o.blender.script));
  h.update(std::string("colmap_oracle=") + (o.colmap ? "1" : "0"));
  return h.hex_digest().substr(0, 24);
}

void copy_tree(const fs::path& from, const fs::path& to) {
  fs::create_directories(to);
  fs::copy(from, to, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
}

}  // namespace

bool weather_generator_available() { return WEATHERGS_HAVE_WEATHER != 0; }

Json GenerateSummary::to_json() const {
  return {{"scene", scene}, {"variant", variant}, {"out_dir", out_dir}, {"cache_entry", cache_entry},
          {"cache_hit", cache_hit}, {"views", views}, {"render_seconds", render_s}, {"weather_seconds", weather_s},
          {"colmap_seconds", colmap_s}, {"total_seconds", total_s}, {"sparse", stats_json(sparse)},
          {"sparse_clean", stats_json(sparse_clean)}};
}

std::string default_cache_dir() {
  if (const char* c = std::getenv("WEATHERGS_CACHE"); c && *c) return c;
  if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x) return std::string(x) + "/weathergs";
  if (const char* h = std::getenv("HOME"); h && *h) return std::string(h) + "/.cache/weathergs";
  throw InputError("--cache", "no cache directory: set --cache, WEATHERGS_CACHE or HOME");
}

std::string ensure_clean_render(const SceneSpec& scene, const std::string& variant, const GenerateOptions& o,
                                bool* cache_hit, double* seconds) {
  const auto start = std::chrono::steady_clock::now();
  const fs::path root = fs::path(o.cache_dir.empty() ? default_cache_dir() : o.cache_dir) / "clean";
  fs::create_directories(root);
  const fs::path entry = root / (scene.name + "_" + variant + "_" + o.profile + "_" + cache_key(scene, variant, o));
  // Entries appear atomically (AtomicDirectory), so an existing one is complete.
  if (fs::exists(entry / "dataset.json")) {
    if (cache_hit) *cache_hit = true;
    if (seconds) *seconds = seconds_since(start);
    return entry.string();
  }
  AtomicDirectory dir(entry.string());
  // render_clean_dataset is atomic itself: it replaces the (empty) staging directory on success.
  render_clean_dataset(scene, variant, o.profile, dir.path(), o.blender);
  if (o.colmap) {
    const Dataset ds = read_dataset(dir.path());
    const fs::path model = fs::path(dir.path()) / "sparse_clean" / "0";
    triangulate_known_poses(ds.cameras, (fs::path(dir.path()) / "clean").string(),
                            (fs::path(dir.path()) / "logs" / "colmap_clean").string(), model.string(), o.colmap_options);
  }
  dir.commit();
  if (cache_hit) *cache_hit = false;
  if (seconds) *seconds = seconds_since(start);
  return entry.string();
}

GenerateSummary generate_variant(const std::string& scene_path, const std::string& variant_name,
                                 const std::string& out_dir, const GenerateOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  const SceneSpec scene = read_scene_spec(scene_path);
  const VariantSpec variant = scene.variant(variant_name);
  scene.profile(o.profile);  // fail on a bad profile before rendering
  const bool has_weather = variant.weather.is_object();
  if (has_weather && !weather_generator_available())
    throw InputError(scene.file + ":/variants/" + variant.name + "/weather",
                     "this build has no weather generator (generator/weather.h); only variants without "
                     "airborne weather (e.g. \"clear\") can be generated");

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
#if WEATHERGS_HAVE_WEATHER
    WeatherRunOptions wopts;
    wopts.seed = o.seed;
    wopts.name = name;
    const JsonReader spec(variant.weather, scene.file, "/variants/" + variant.name + "/weather");
    run_weather(s.cache_entry, spec, root.string(), wopts);
#endif
  } else {
    for (const char* folder : {"clean", "images", "depth"}) copy_tree(fs::path(s.cache_entry) / folder, root / folder);
    fs::copy_file(fs::path(s.cache_entry) / "cameras.json", root / "cameras.json");
    fs::copy_file(fs::path(s.cache_entry) / "dataset.json", root / "dataset.json");
  }
  s.weather_s = seconds_since(t);

  Dataset ds = read_dataset(root.string());
  s.views = int(ds.cameras.size());
  t = std::chrono::steady_clock::now();
  if (o.colmap) {
    // What a method would really get: features of the weather images, with the known poses.
    const fs::path sparse = root / "sparse";
    fs::remove_all(sparse);
    TriangulationResult tri = triangulate_known_poses(ds.cameras, (root / "images").string(),
                                                      (root / "logs" / "colmap").string(), (sparse / "0").string(),
                                                      o.colmap_options);
    s.sparse = tri.stats;
    // The oracle: the same from the clean images (cached with the render).
    copy_tree(fs::path(s.cache_entry) / "sparse_clean", root / "sparse_clean");
    s.sparse_clean = analyze_model((root / "sparse_clean" / "0").string(), o.colmap_options,
                                   (root / "logs" / "colmap" / "colmap.log").string());
  }
  s.colmap_s = seconds_since(t);
  write_transforms_json((root / "transforms.json").string(), ds.cameras);

  // dataset.json: our name and weather; the pipeline's stages next to the generator's.
  ds.info.name = name;
  ds.info.scene = scene.name;
  ds.info.weather = variant.name;
  Json gen = ds.info.generator ? *ds.info.generator : Json::object();
  if (!gen.contains("stages") || !gen["stages"].is_array()) gen["stages"] = Json::array();
  Json stages = Json::array();
  stages.push_back({{"name", "blender"}, {"seconds", s.render_s}, {"cached", s.cache_hit}});
  for (const auto& st : gen["stages"])
    if (!(st.is_object() && st.value("name", "") == "blender")) stages.push_back(st);
  if (o.colmap) stages.push_back({{"name", "colmap"}, {"seconds", s.colmap_s}});
  gen["stages"] = stages;
  gen["scene_spec"] = scene.file;
  gen["profile"] = o.profile;
  gen["variant"] = variant.name;
  gen["surface"] = variant.surface;
  gen["clean_render"] = fs::path(s.cache_entry).filename().string();
  if (o.colmap) gen["colmap"] = {{"sparse", stats_json(s.sparse)}, {"sparse_clean", stats_json(s.sparse_clean)}};
  ds.info.generator = gen;
  write_dataset_json((root / "dataset.json").string(), ds.info);
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
    spec.profile(o.profile);
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
    summaries.push_back(generate_variant(it.scene, it.weather, (fs::path(out_dir) / (spec.name + "_" + it.weather)).string(), o));
    bar.tick();
  }
  bar.finish();
  Json all = Json::array();
  for (const auto& s : summaries) all.push_back(s.to_json());
  write_file_atomic((fs::path(out_dir) / "summary.json").string(),
                    Json{{"suite", suite_name}, {"profile", o.profile}, {"total_seconds", seconds_since(start)},
                         {"variants", all}}
                        .dump(1));
  return summaries;
}

}  // namespace weathergs::pipeline
