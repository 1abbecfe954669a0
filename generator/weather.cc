#include "generator/weather.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <set>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/dataset_identity.h"
#include "core/error.h"
#include "core/image.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "generator/lens/lens_stage.h"
#include "generator/overlay.h"
#include "generator/stages.h"

#include "generator/weather_spec.h"

namespace weathergs::generator {

namespace fs = std::filesystem;

namespace {
constexpr const char* kGeneratorVersion = "weathergs-generator 1";
constexpr double kSkyFraction = 0.005;  // brightest 0.5% of the pixels
// The keys of dataset.json's generator block that the weather stage owns.
constexpr const char* kWeatherKeys[] = {"version", "seed", "spec", "sky_radiance", "counters",
                                        "outputs", "airlight", "lens_droplets"};

double luminance(const Image& img, size_t p) {
  return 0.2126 * img.data[p * img.channels] + 0.7152 * img.data[p * img.channels + 1] +
         0.0722 * img.data[p * img.channels + 2];
}

// The stages the spec calls for, in pipeline order.
std::vector<std::unique_ptr<WeatherStage>> make_stages(const WeatherSpec& spec, const Eigen::Vector3f& airlight,
                                                       bool manifest, const Camera& reference) {
  std::vector<std::unique_ptr<WeatherStage>> stages;
  if (spec.fog) stages.push_back(std::make_unique<FogStage>(spec.fog->beta_per_m, airlight));
  for (const auto* effect : {&spec.rain, &spec.snow})
    if (*effect)
      stages.push_back(std::make_unique<ParticleStage>(**effect, (*effect)->render_for(spec.render), spec.seed,
                                                       manifest, spec.sun));
  // The paper style's per-view 2D layers come after the world-space particles (the paper's OpenCV
  // step ran on the rendered images).
  for (const auto* effect : {&spec.rain, &spec.snow})
    if (*effect && (*effect)->overlay && (*effect)->overlay->count_per_mpx > 0)
      stages.push_back(std::make_unique<OverlayStage>(*(*effect)->overlay, spec.seed));
  // Lens droplets last: the drops on the glass see the weathered scene (docs/lens_droplets.md).
  if (spec.lens_droplets)
    stages.push_back(std::make_unique<lens::LensDropletStage>(*spec.lens_droplets, spec.seed, reference));
  return stages;
}

std::string clean_image_path(const Dataset& d, const std::string& view) {
  const std::string p = d.clean_or_input_path(view);
  if (!fs::exists(p)) throw InputError(p, "no clean image for view '" + view + "'");
  return p;
}

// Float EXR layer (core's writer is byte-reproducible: no write-time stamp).
void write_layer_exr(const std::string& path, const Image& img) {
  Image layer = img;
  layer.space = ColorSpace::kLinear;
  ImageWriteOptions options{PixelFormat::kFloat32, {}};
  if (img.channels == 1) options.channel_names = {"Y"};
  write_image(path, layer, options);
}

}  // namespace

void WeatherRunOptions::validate() const {
  if (!(mask_threshold > 0 && mask_threshold <= 1))
    throw InputError("mask_threshold", "must be in (0, 1], got " + std::to_string(mask_threshold));
}

Eigen::Vector3f mean_sky_radiance(const std::vector<std::array<double, 3>>& per_view) {
  WGS_CHECK(!per_view.empty());
  std::array<double, 3> s{0, 0, 0};
  for (const auto& v : per_view)
    for (int c = 0; c < 3; ++c) s[size_t(c)] += v[size_t(c)];
  Eigen::Vector3f sky;
  for (int c = 0; c < 3; ++c) sky[c] = float(s[size_t(c)] / double(per_view.size()));
  return sky;
}

std::array<double, 3> estimate_sky_radiance(const Image& img) {
  const size_t n = img.num_pixels();
  std::vector<std::pair<double, size_t>> lum(n);
  for (size_t p = 0; p < n; ++p) lum[p] = {luminance(img, p), p};
  const size_t k = std::max<size_t>(1, size_t(double(n) * kSkyFraction));
  std::nth_element(lum.begin(), lum.begin() + long(k - 1), lum.end(), std::greater<>());
  std::sort(lum.begin(), lum.begin() + long(k), std::greater<>());  // fixed summation order
  std::array<double, 3> s{0, 0, 0};
  for (size_t i = 0; i < k; ++i)
    for (int c = 0; c < 3; ++c) s[size_t(c)] += img.data[lum[i].second * img.channels + c];
  for (double& v : s) v /= double(k);
  return s;
}

Json run_weather(const std::string& clean_dir, const JsonReader& spec_reader, const std::string& out_dir,
                 const WeatherRunOptions& options) {
  options.validate();
  WeatherSpec spec = parse_weather_spec(spec_reader, options.style);
  if (options.seed) spec.seed = *options.seed;
  const Dataset clean = read_dataset(clean_dir);

  // Effective cameras and processing order.
  std::vector<Camera> cameras;
  for (const Camera& c : clean.cameras) {
    Camera e = spec.camera.apply(c);
    validate_camera(e, spec_reader.where("camera") + " applied to view '" + c.name + "'");
    if (spec.render.defocus) thin_lens_of(e);  // focus beyond the focal length, else InputError
    cameras.push_back(e);
  }
  std::vector<size_t> order;
  if (options.view_order.empty()) {
    for (size_t i = 0; i < cameras.size(); ++i) order.push_back(i);
  } else {
    std::map<std::string, size_t> index;
    for (size_t i = 0; i < cameras.size(); ++i) index[cameras[i].name] = i;
    std::set<size_t> seen;
    for (const std::string& v : options.view_order) {
      auto it = index.find(v);
      if (it == index.end()) throw InputError("view_order", "no view named '" + v + "'");
      if (!seen.insert(it->second).second) throw InputError("view_order", "view '" + v + "' listed twice");
      order.push_back(it->second);
    }
    if (order.size() != cameras.size()) throw InputError("view_order", "must list every view exactly once");
  }

  // Dataset-wide sky radiance (ambient light of the particles, airlight of the fog when "auto").
  std::vector<std::array<double, 3>> sky_per_view(cameras.size());
  parallel_for(0, int64_t(cameras.size()), [&](int64_t i) {
    const Image img = to_linear(to_rgb(read_image(clean_image_path(clean, cameras[size_t(i)].name))));
    sky_per_view[size_t(i)] = estimate_sky_radiance(img);
  });
  const Eigen::Vector3f sky = mean_sky_radiance(sky_per_view);
  const Eigen::Vector3f airlight = spec.fog && spec.fog->airlight ? *spec.fog->airlight : sky;

  // The lens glass is placed against the first camera in cameras.json order, whatever the view order.
  if (spec.lens_droplets) spec.lens_droplets = lens::resolve_lens_droplet_spec(*spec.lens_droplets, cameras.front());
  const std::vector<std::unique_ptr<WeatherStage>> stages =
      make_stages(spec, airlight, options.write_manifest, cameras.front());

  AtomicDirectory out(out_dir);
  const fs::path root(out.path());
  Dataset result;
  result.root = root.string();
  for (ImageKind k : {ImageKind::kImages, ImageKind::kClean, ImageKind::kDepth}) fs::create_directories(result.dir(k));
  if (options.write_targets)
    for (ImageKind k : {ImageKind::kTargetNoParticles, ImageKind::kTargetLensOnly}) fs::create_directories(result.dir(k));

  const size_t n_views = cameras.size();
  std::vector<std::vector<double>> seconds(n_views, std::vector<double>(stages.size(), 0.0));
  std::vector<std::map<std::string, int64_t>> counters(n_views);
  std::vector<std::set<std::string>> layer_names(n_views), text_names(n_views);
  std::vector<Json> lens_drops(n_views);
  ProgressBar progress("weather", int64_t(n_views));
  parallel_for(0, int64_t(n_views), [&](int64_t oi) {
    const size_t i = order[size_t(oi)];
    const Camera& cam = cameras[i];
    const std::string src = clean_image_path(clean, cam.name);
    const Image clean_img = to_linear(to_rgb(read_image(src)));
    if (clean_img.width != cam.width || clean_img.height != cam.height)
      throw InputError(src, "image is " + clean_img.to_string() + " but cameras.json says " +
                                std::to_string(cam.width) + "x" + std::to_string(cam.height));
    const std::string depth_path = clean.path(ImageKind::kDepth, cam.name);
    if (!fs::exists(depth_path)) throw InputError(depth_path, "the weather generator needs the clean depth");
    const Image depth = read_depth(depth_path);
    if (depth.width != cam.width || depth.height != cam.height)
      throw InputError(depth_path, "depth is " + depth.to_string() + ", expected the camera size");
    const EnvironmentLight env = make_environment_light(clean_img, sky);
    WeatherView view(cam, clean_img, depth, env);
    for (size_t s = 0; s < stages.size(); ++s) {
      const auto start = std::chrono::steady_clock::now();
      stages[s]->run(view);
      seconds[i][s] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    require_finite(view.radiance, "internal: weathered view '" + cam.name + "'");
    write_image(result.path(ImageKind::kImages, cam.name), view.radiance);
    if (options.write_targets) {
      // The same stages (same seed, same drops) without the particle stages, and the lens alone on
      // the clean view: exact targets for the restoration filters (docs/generator.md, "Targets").
      WeatherView no_particles(cam, clean_img, depth, env), lens_only(cam, clean_img, depth, env);
      for (const auto& stage : stages) {
        if (stage->kind() != StageKind::kParticles) stage->run(no_particles);
        if (stage->kind() == StageKind::kLens) stage->run(lens_only);
      }
      write_image(result.path(ImageKind::kTargetNoParticles, cam.name), no_particles.radiance);
      write_image(result.path(ImageKind::kTargetLensOnly, cam.name), lens_only.radiance);
    }
    if (fs::path(src).extension() == layout::kImageExt) fs::copy_file(src, result.path(ImageKind::kClean, cam.name));
    else write_image(result.path(ImageKind::kClean, cam.name), clean_img);
    fs::copy_file(depth_path, result.path(ImageKind::kDepth, cam.name));
    if (view.has_particles) {
      fs::create_directories(result.dir(ImageKind::kParticleMask));
      write_mask(result.path(ImageKind::kParticleMask, cam.name), view.particle_alpha, float(options.mask_threshold));
      view.layers["particle_alpha"] = view.particle_alpha;
    }
    if (view.lens_mask) {
      fs::create_directories(result.dir(ImageKind::kLensMask));
      write_mask(result.path(ImageKind::kLensMask, cam.name), *view.lens_mask);
      lens_drops[i] = std::move(view.lens_drops);
    }
    if (options.write_layers)
      for (const auto& [name, img] : view.layers) {
        const std::string path = result.layer_path(name, cam.name);
        fs::create_directories(fs::path(path).parent_path());
        write_layer_exr(path, img);
        layer_names[i].insert(name);
      }
    for (const auto& [name, text] : view.texts) {
      const std::string path = result.layer_path(name, cam.name, ".csv");
      fs::create_directories(fs::path(path).parent_path());
      write_file_atomic(path, text);
      text_names[i].insert(name);
    }
    counters[i] = view.counters;
    progress.tick();
  });
  progress.finish();

  // The input's exports describe the same cameras: carried over unless the caller makes its own.
  if (options.copy_exports) {
    const fs::path in_root(clean_dir);
    if (fs::is_directory(in_root / layout::kSparseDir)) copy_tree(in_root / layout::kSparseDir, root / layout::kSparseDir);
    if (fs::exists(in_root / layout::kTransformsJson))
      fs::copy_file(in_root / layout::kTransformsJson, root / layout::kTransformsJson);
  }

  // The generator block: sums in view (cameras.json) order.
  Json stage_list = Json::array();
  for (size_t s = 0; s < stages.size(); ++s) {
    double total = 0;
    for (size_t i = 0; i < n_views; ++i) total += seconds[i][s];
    stage_list.push_back({{"name", stages[s]->name()}, {"seconds", total}});
  }
  std::map<std::string, int64_t> total_counters;
  std::set<std::string> layers, texts;
  for (size_t i = 0; i < n_views; ++i) {
    for (const auto& [k, v] : counters[i]) total_counters[k] += v;
    layers.insert(layer_names[i].begin(), layer_names[i].end());
    texts.insert(text_names[i].begin(), text_names[i].end());
  }
  // One straight line: the stages before this one (e.g. capture's Blender render) keep their entries;
  // the weather adds its own keys and appends its stages. Re-weathering a weathered dataset replaces
  // the weather's keys only.
  Json block = clean.info.generator && clean.info.generator->is_object() ? *clean.info.generator : Json::object();
  Json stages_before = block.contains("stages") && block["stages"].is_array() ? block["stages"] : Json::array();
  for (const char* key : kWeatherKeys) block.erase(key);
  block["version"] = kGeneratorVersion;
  block["seed"] = spec.seed;
  block["spec"] = spec.to_json();
  for (const Json& st : stage_list) stages_before.push_back(st);
  block["stages"] = stages_before;
  block["sky_radiance"] = {sky[0], sky[1], sky[2]};
  block["counters"] = total_counters;
  block["outputs"] = {{"mask_threshold", options.mask_threshold}, {"float_layers", layers}, {"manifests", texts},
                      {"targets", options.write_targets}};
  if (spec.fog) block["airlight"] = {airlight[0], airlight[1], airlight[2]};
  if (spec.lens_droplets) block["lens_droplets"] = {{"views", lens_drops}};  // cameras.json order

  result.cameras = cameras;
  result.info.name = options.name.empty() ? clean.info.name + "_" + spec.weather_name() : options.name;
  result.info.scene = clean.info.scene;
  result.info.weather = spec.weather_name();
  result.info.splits = clean.info.splits;
  result.info.splits_rule = clean.info.splits_rule;
  result.info.generator = block;
  write_dataset(result);
  record_dataset_identity(root.string());
  out.commit();
  return block;
}

}  // namespace weathergs::generator
