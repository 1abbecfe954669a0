#include "restoration/aef/filter_dataset.h"

#include <chrono>
#include <filesystem>
#include <optional>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/error.h"
#include "core/image.h"
#include "core/json_reader.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "restoration/aef/aef_plugin.h"

namespace weathergs::restoration::aef {

namespace fs = std::filesystem;

const char* to_string(FilterMode m) { return m == FilterMode::kMask ? "mask" : "restore"; }
const char* to_string(FilterMethod m) { return m == FilterMethod::kLearned ? "learned" : "tophat"; }
const char* to_string(SelectScope s) { return s == SelectScope::kPerView ? "per-view" : "per-scene"; }
const char* to_string(AefTask t) {
  switch (t) {
    case AefTask::kAlways: return "always";
    case AefTask::kAuto: return "auto";
    case AefTask::kDerain: return "derain";
    case AefTask::kDesnow: return "desnow";
    case AefTask::kNone: return "none";
  }
  return "?";
}

void FilterDatasetOptions::validate() const {
  filter.validate();
  if (input != ImageKind::kImages && input != ImageKind::kClean)
    throw InputError("filter options input", "must be the dataset's images or clean images");
  if (!(alpha_threshold > 0 && alpha_threshold < 1))
    throw InputError("filter options alpha_threshold", "expected in (0, 1), got " + std::to_string(alpha_threshold));
  if (method == FilterMethod::kLearned && task == AefTask::kAlways && instruction.empty())
    throw InputError("filter options task", "\"always\" has no learned plugin: the learned AEF needs auto, derain, desnow or none");
  const bool needs_weights = (method == FilterMethod::kLearned && task != AefTask::kNone) || (task == AefTask::kAuto && instruction.empty());
  if (needs_weights && aef_weights.empty())
    throw InputError("filter options aef_weights", "empty: the learned AEF and the selector need a weights folder (models/aef)");
}

namespace {

struct Models {
  std::optional<WeatherSelector> selector;
  std::optional<AefPlugin> derain, desnow;
  Json files = Json::object();  // stem -> sha256
};

std::string stem_in(const std::string& dir, const char* stem) { return (fs::path(dir) / stem).string(); }

// The plugins and selector the options need, loaded before anything is written.
Models load_models(const FilterDatasetOptions& o, bool select, bool need_derain, bool need_desnow) {
  Models m;
  auto record = [&](const std::string& stem, const Json& meta) { m.files[stem] = meta.value("weights_sha256", ""); };
  if (select) {
    m.selector = WeatherSelector::load(stem_in(o.aef_weights, kSelectorStem));
    record(stem_in(o.aef_weights, kSelectorStem), m.selector->metadata());
  }
  if (o.method == FilterMethod::kLearned && need_derain) {
    m.derain = AefPlugin::load(stem_in(o.aef_weights, kDerainStem), AefPluginKind::kDerain);
    record(stem_in(o.aef_weights, kDerainStem), m.derain->metadata());
  }
  if (o.method == FilterMethod::kLearned && need_desnow) {
    m.desnow = AefPlugin::load(stem_in(o.aef_weights, kDesnowStem), AefPluginKind::kDesnow);
    record(stem_in(o.aef_weights, kDesnowStem), m.desnow->metadata());
  }
  return m;
}

Image read_checked(const Dataset& ds, ImageKind kind, const Camera& c) {
  const std::string path = ds.path(kind, c.name);
  const Image img = read_image(path);
  if (img.width != c.width || img.height != c.height)
    throw InputError(path, "is " + img.to_string() + ", cameras.json says " + std::to_string(c.width) + "x" + std::to_string(c.height));
  if (img.channels != 3 && img.channels != 4) throw InputError(path, "expected an RGB or RGBA image, got " + img.to_string());
  return to_rgb(img);
}

Json cosines_json(const std::array<double, kWeatherClasses>& c) {
  return {{to_string(WeatherClass::kSnow), c[0]}, {to_string(WeatherClass::kRain), c[1]}, {to_string(WeatherClass::kNone), c[2]}};
}

const char* plugin_name(WeatherClass c) { return c == WeatherClass::kRain ? "derain" : c == WeatherClass::kSnow ? "desnow" : "none"; }

}  // namespace

Json filter_settings_json(const FilterDatasetOptions& o, int width) {
  Json j{{"method", to_string(o.method)},
         {"task", to_string(o.task)},
         {"input", o.input == ImageKind::kClean ? "clean" : "images"},
         {"mode", to_string(o.mode)}};
  if (!o.instruction.empty()) j["instruction"] = o.instruction;
  if (o.method == FilterMethod::kTopHat)
    j["parameters"] = {{"radius_px_at_300", o.filter.radius_px_at_300},
                       {"radius_px", width > 0 ? o.filter.radius_px(width) : 0},
                       {"threshold", o.filter.threshold},
                       {"dilate_px", o.filter.dilate_px}};
  else
    j["parameters"] = {{"alpha_threshold", o.alpha_threshold}};
  return j;
}

std::string filter_settings_mismatch(const Json& report, const FilterDatasetOptions& o, int width) {
  if (std::string why = settings_mismatch(report, filter_settings_json(o, width)); !why.empty()) return why;
  // The weight files, by their content: the same network in another folder is the same filter.
  if (report.contains("weights"))
    for (const auto& [stem, sha] : report.at("weights").items()) {
      const std::string name = fs::path(stem).filename().string();
      const fs::path manifest = fs::path(o.aef_weights) / (name + ".json");
      const std::string now = fs::exists(manifest) ? read_json_file(manifest.string()).value("weights_sha256", "") : "";
      if (now != sha.get<std::string>())
        return "weights of " + name + ": holds sha256 " + sha.get<std::string>() + ", asked for " +
               (now.empty() ? manifest.string() + " (missing)" : now);
    }
  return "";
}

StageOutput filter_output(const std::string& out, const FilterDatasetOptions& options, int width) {
  StageOutput s;
  s.record = (fs::path(out) / kFilterReportFile).string();
  if (!fs::exists(s.record)) return s;
  s.why = filter_settings_mismatch(read_json_file(s.record), options, width);
  s.state = s.why.empty() ? StageOutput::State::kComplete : StageOutput::State::kStale;
  return s;
}

FilterDatasetReport filter_dataset(const std::string& dataset, const std::string& out, const FilterDatasetOptions& o) {
  o.validate();
  const auto start = std::chrono::steady_clock::now();
  const Dataset ds = read_dataset(dataset);
  const std::string in_dir = ds.dir(o.input);
  if (!fs::is_directory(in_dir)) throw InputError(in_dir, "missing: the dataset has no such images");
  // Every input must exist before anything is written.
  for (const Camera& c : ds.cameras)
    if (!fs::exists(ds.path(o.input, c.name))) throw InputError(ds.path(o.input, c.name), "missing: view " + c.name);

  // The fixed choice (an instruction or a named task), or nullopt when the selector decides.
  std::optional<WeatherClass> fixed;
  if (!o.instruction.empty()) fixed = class_of_instruction(o.instruction);
  else if (o.task == AefTask::kDerain) fixed = WeatherClass::kRain;
  else if (o.task == AefTask::kDesnow) fixed = WeatherClass::kSnow;
  else if (o.task == AefTask::kNone) fixed = WeatherClass::kNone;
  else if (o.task == AefTask::kAlways) fixed = WeatherClass::kRain;  // top-hat only (validate): rain and snow alike
  const bool select = !fixed.has_value();
  const Models models = load_models(o, select, select || fixed == WeatherClass::kRain, select || fixed == WeatherClass::kSnow);
  // The output folder before any view is processed: a bad --out fails at once, not after the selector.
  AtomicDirectory dir(out);

  FilterDatasetReport report;
  report.views.resize(ds.cameras.size());
  report.selected = select;
  for (size_t i = 0; i < ds.cameras.size(); ++i) {
    report.views[i].view = ds.cameras[i].name;
    report.views[i].plugin = fixed.value_or(WeatherClass::kNone);
  }
  // Selection: every embedding first (per scene needs all of them).
  if (select) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<std::vector<float>> embeddings;
    for (const Camera& c : ds.cameras) embeddings.push_back(models.selector->embed(read_checked(ds, o.input, c), ds.path(o.input, c.name)));
    report.selector_seconds_per_view = seconds_since(t0) / double(std::max<size_t>(1, ds.cameras.size()));
    report.scene = models.selector->select(WeatherSelector::mean_embedding(embeddings));
    for (size_t i = 0; i < embeddings.size(); ++i) {
      const Selection s = models.selector->select(embeddings[i]);
      report.views[i].selected = true;
      report.views[i].cosine = s.cosine;
      report.views[i].plugin = o.scope == SelectScope::kPerView ? s.choice : report.scene.choice;
    }
  }

  if (o.mode == FilterMode::kRestore) fs::create_directories(fs::path(dir.path()) / kFilterMasksDir);
  auto filter_one = [&](size_t i) {
    const auto t0 = std::chrono::steady_clock::now();
    const Camera& c = ds.cameras[i];
    const std::string path = ds.path(o.input, c.name);
    const Image img = read_checked(ds, o.input, c);
    FilterViewReport& v = report.views[i];
    Image restored = img, mask(img.width, img.height, 1, ColorSpace::kLinear);
    if (v.plugin != WeatherClass::kNone && o.method == FilterMethod::kTopHat) {
      ParticleFilterResult r = filter_particles(img, o.filter, path);
      restored = std::move(r.restored);
      mask = std::move(r.mask);
    } else if (v.plugin != WeatherClass::kNone) {
      AefOutput r = (v.plugin == WeatherClass::kRain ? *models.derain : *models.desnow).restore(img, path);
      restored = std::move(r.restored);
      for (size_t k = 0; k < mask.data.size(); ++k) mask.data[k] = r.alpha.data[k] >= o.alpha_threshold ? 1.f : 0.f;
    }
    size_t masked = 0;
    for (float m : mask.data) masked += m > 0.5f;
    v.mask_fraction = double(masked) / double(std::max<size_t>(1, mask.data.size()));
    const std::string name = c.name + layout::kImageExt;
    if (o.mode == FilterMode::kRestore) {
      write_image((fs::path(dir.path()) / name).string(), restored);
      write_mask((fs::path(dir.path()) / kFilterMasksDir / name).string(), mask);
    } else {
      write_mask((fs::path(dir.path()) / name).string(), mask);
    }
    v.seconds = seconds_since(t0);
  };
  // Views in parallel, each on one thread (the learned plugins included: AefPlugin::restore), so the
  // output does not depend on the thread count (tests restoration/particle_filter, restoration/aef).
  parallel_for(0, int64_t(ds.cameras.size()), [&](int64_t i) { filter_one(size_t(i)); });
  report.seconds = seconds_since(start);

  Json views = Json::array();
  for (const FilterViewReport& v : report.views) {
    Json j{{"view", v.view}, {"plugin", plugin_name(v.plugin)}, {"mask_fraction", v.mask_fraction}, {"seconds", v.seconds}};
    if (v.selected) j["cosine"] = cosines_json(v.cosine);
    views.push_back(j);
  }
  Json j = filter_settings_json(o, ds.cameras.empty() ? 0 : ds.cameras.front().width);
  j.update(Json{{"format", "weathergs-filter"},
                {"version", 2},
                {"dataset", fs::absolute(dataset).lexically_normal().string()},
                {"seconds", report.seconds},
                {"seconds_per_view", report.seconds / double(std::max<size_t>(1, ds.cameras.size()))},
                {"views", views}});
  if (!models.files.empty()) j["weights"] = models.files;
  if (select) {
    j["selection"] = {{"scope", to_string(o.scope)},
                      {"theta", models.selector->theta()},
                      {"scene_plugin", plugin_name(report.scene.choice)},
                      {"scene_cosine", cosines_json(report.scene.cosine)},
                      {"instructions", {{"desnow", kInstructionDesnow}, {"derain", kInstructionDerain}, {"none", kInstructionNone}}},
                      {"selector_seconds_per_view", report.selector_seconds_per_view}};
  }
  write_file_atomic((fs::path(dir.path()) / kFilterReportFile).string(), j.dump(2) + "\n");
  dir.commit();
  return report;
}

}  // namespace weathergs::restoration::aef
