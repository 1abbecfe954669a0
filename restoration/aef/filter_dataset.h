// `weathergs filter`: the Atmospheric Effect Filter over every view of a dataset (docs/restoration.md):
// the classical top-hat (restoration/aef/particle_filter.h) or the learned derain/desnow plugins
// (restoration/aef/aef_plugin.h), with the weather selector (restoration/aef/weather_selector.h) deciding
// which plugin, if any, runs.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/dataset_layout.h"
#include "core/stage_output.h"
#include "restoration/aef/particle_filter.h"
#include "restoration/aef/weather_selector.h"

namespace weathergs::restoration::aef {

// restore: <out>/<view>.png are the filtered images (train 3DGS on them: train --images-dir) and
//          <out>/masks/<view>.png the particle masks; mask: <out>/<view>.png are the particle masks
//          only (255 = particle: train on the raw pixels elsewhere with train --masks-dir).
enum class FilterMode { kRestore, kMask };
inline constexpr const char* kFilterMasksDir = "masks";          // restore mode: <out>/masks/<view>.png
inline constexpr const char* kFilterReportFile = "filter.json";  // written last: the output is complete
const char* to_string(FilterMode m);

// tophat: the classical filter (no weights; one filter for rain and snow alike). learned: the derain
// and desnow plugins (weights in `aef_weights`).
enum class FilterMethod { kTopHat, kLearned };
const char* to_string(FilterMethod m);

// Which plugin runs on which view.
//   always: the filter on every view, no selection (the top-hat's behaviour before the selector; the
//           learned AEF has no plugin for "any weather" and refuses it);
//   auto:   the weather selector decides, per scene or per view; `none` leaves the view unchanged;
//   derain / desnow: that plugin on every view (for the top-hat both mean "filter"); none: no view is
//           filtered (the output is a copy, the masks are empty).
enum class AefTask { kAlways, kAuto, kDerain, kDesnow, kNone };
const char* to_string(AefTask t);

// auto's granularity: per scene (the normalized mean embedding of all views: one plugin for the
// dataset) or per view (the paper's eq. 4 for each image).
enum class SelectScope { kPerScene, kPerView };
const char* to_string(SelectScope s);

// The weights in a folder: <dir>/derain.{json,bin}, <dir>/desnow.{json,bin}, <dir>/selector.{json,bin}.
inline constexpr const char* kDerainStem = "derain";
inline constexpr const char* kDesnowStem = "desnow";
inline constexpr const char* kSelectorStem = "selector";

struct FilterDatasetOptions {
  ImageKind input = ImageKind::kImages;  // which images to filter (kImages or kClean)
  FilterMode mode = FilterMode::kRestore;
  FilterMethod method = FilterMethod::kTopHat;
  AefTask task = AefTask::kAlways;
  // Non-empty: the plugin named by this instruction (class_of_instruction), overriding `task`.
  std::string instruction;
  SelectScope scope = SelectScope::kPerScene;
  std::string aef_weights;  // folder of the learned weights (needed by learned, and by auto)
  ParticleFilterOptions filter;  // the top-hat's parameters
  double alpha_threshold = 0.5;  // learned: the particle mask is alpha >= this
  void validate() const;         // InputError naming the field
};

struct FilterViewReport {
  std::string view;
  WeatherClass plugin = WeatherClass::kNone;  // which plugin ran (snow = desnow, rain = derain)
  bool selected = false;                      // whether `cosine` holds the selector's per-view cosines
  std::array<double, kWeatherClasses> cosine{};
  double mask_fraction = 0;
  double seconds = 0;
};
struct FilterDatasetReport {
  std::vector<FilterViewReport> views;  // dataset order
  bool selected = false;                // whether the selector ran
  Selection scene;                      // per-scene selection (when selected)
  double selector_seconds_per_view = 0;
  double seconds = 0;
};

// The keys of filter.json that decide its images (method, task, input, mode, instruction, the
// parameters; `width`: the dataset's, for the top-hat's radius). filter_dataset writes them.
Json filter_settings_json(const FilterDatasetOptions& options, int width);
// Whether a filter.json was made with `options`: "" if so, else the first difference ("KEY: holds A,
// asked for B"), the weight files compared by sha256. How a resumed run decides to reuse its output.
std::string filter_settings_mismatch(const Json& report, const FilterDatasetOptions& options, int width);
// What `out` holds against `options` (dataset width `width`): complete when its filter.json matches,
// stale naming the first difference, absent without filter.json (written last).
StageOutput filter_output(const std::string& out, const FilterDatasetOptions& options, int width);

// Every view of the dataset; `out` is written atomically with filter.json (method, task, weights,
// per-view plugin, cosines, mask fraction, seconds). Every input and every weight file is checked
// before anything is written; InputError names the dataset, view, file or option.
FilterDatasetReport filter_dataset(const std::string& dataset, const std::string& out, const FilterDatasetOptions& options);

}  // namespace weathergs::restoration::aef
