// Training and held-out evaluation of the learned AEF plugins and the weather selector on generated
// datasets (docs/restoration.md, `weathergs train-aef`, `make models`). libtorch-free.
#pragma once

#include <string>
#include <vector>

#include "core/dataset.h"
#include "restoration/aef/aef_plugin.h"
#include "restoration/aef/weather_selector.h"

namespace weathergs::restoration::aef {

// A dataset's weather class from dataset.json's `weather` ("rain+fog" is rain; clear, fog only or
// lens drops only are none). InputError when it names both rain and snow.
WeatherClass weather_class_of(const Dataset& ds);
// The class the selector should pick: weather_class_of, except that a weathered dataset whose particles
// the camera barely sees (mean PSNR of images/ against targets/no_particles above
// kInvisibleParticlesPsnrDb, i.e. an RMS change under 1%) is none: no plugin can help there, and the
// plugins cost 3 to 30 dB on such views (held-out market_w05/w07/w10 in docs/restoration.md).
inline constexpr double kInvisibleParticlesPsnrDb = 40;
WeatherClass selector_class_of(const Dataset& ds);
// The class a plugin removes.
WeatherClass class_of(AefPluginKind kind);

// Every view of a dataset: images/<view>.png, its no-particle target (targets/no_particles/, or the
// image itself when the dataset has no particles) and masks/particles/ (zero when absent).
std::vector<AefExample> read_aef_examples(const std::string& dataset);

struct AefHeldOutScore {
  std::string dataset;
  int views = 0;
  double psnr_input = 0;     // mean PSNR (dB) of the input against the no-particle target
  double psnr_restored = 0;  // the same for the plugin's output
};
// Mean PSNRs over every view of each dataset.
std::vector<AefHeldOutScore> score_aef(const AefPlugin& plugin, const std::vector<std::string>& datasets);

struct TrainAefOptions {
  AefTrainOptions train;
  std::string command;  // recorded in the manifest
};
struct TrainAefResult {
  AefTrainRecord record;
  std::vector<AefHeldOutScore> held_out;
  size_t examples = 0;
};
// Trains `kind` on the views of `train_datasets` whose class is the plugin's or none (clear views
// teach it to leave a view alone), scores it on the held-out datasets of those classes, and writes
// <out_stem>.json/.bin with the record.
TrainAefResult train_aef(AefPluginKind kind, const std::vector<std::string>& train_datasets,
                         const std::vector<std::string>& held_out, const std::string& out_stem, const TrainAefOptions& options);

struct SelectorCalibration {
  double theta = 0.5;
  double view_accuracy = 0;   // held-out views, per-view decisions at theta
  double scene_accuracy = 0;  // held-out datasets, per-scene (mean embedding) decisions at theta
  int views = 0, scenes = 0;
  Json per_dataset = Json::array();
};
// theta on a grid -1..1 (step 0.01) maximizing the per-view accuracy over the held-out views (ties:
// the theta in the middle of the best run).
SelectorCalibration calibrate_selector(const WeatherSelector& selector, const std::vector<std::string>& held_out);

struct TrainSelectorOptions {
  SelectorTrainOptions train;
  std::string command;
};
struct TrainSelectorResult {
  SelectorTrainRecord record;
  SelectorCalibration calibration;
  size_t examples = 0;
};
TrainSelectorResult train_selector(const std::vector<std::string>& train_datasets, const std::vector<std::string>& held_out,
                                   const std::string& out_stem, const TrainSelectorOptions& options);

}  // namespace weathergs::restoration::aef
