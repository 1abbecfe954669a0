// Training and calibration of the Lens Effect Detector on generated datasets (docs/restoration_led.md,
// `weathergs train-led`, `make models`). libtorch-free.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "restoration/led/detect_dataset.h"
#include "restoration/led/lens_detector.h"

namespace weathergs::restoration::led {

// Every view of a dataset as (images/<view>.png, masks/lens/<view>.png); a dataset without masks/lens
// has no drops: its masks are zero.
std::vector<LedExample> read_led_examples(const std::string& dataset);

struct LedCalibration {
  double threshold = 0.5;
  int dilate_iterations = kReleasedCodeDilations;
  double mean_iou = 0;                  // over the held-out datasets with drops
  double mean_precision = 0;            // the same datasets
  std::vector<LedScore> scores;         // at the chosen threshold and dilations
  // With search_peak: the peak-relative rule chosen for the same dilations, its mean IoU and scores.
  std::optional<LedPeakRule> peak;
  double peak_mean_iou = 0;
  double peak_mean_precision = 0;
  std::vector<LedScore> peak_scores;
};
// The dilation counts a calibration with search_dilations tries: none up to the released code's three.
inline constexpr int kMaxCalibratedDilations = kReleasedCodeDilations;

// One held-out dataset as a calibration sees it: the attention averaged over its training views and
// their per-view truth (masks/lens; zero masks for a dataset without drops).
struct LedHeldOutMap {
  std::string name;
  Image attention;
  std::vector<Image> truth;
  bool has_drops = false;
};
// The map of `dataset` from the network (mean_attention over its training views).
LedHeldOutMap held_out_map(const LensDetector& led, const std::string& dataset);
// What `weathergs detect --save-attention` wrote to `detect_dir` (train-views averaging): the
// averaged map, with the truth of the dataset its detect.json names, the sha256 of the weights that
// made it and its "adaptation" block (null unless made with --adapt). InputError naming the folder
// when it is not a finished detect output with saved attention.
struct SavedLedMap {
  LedHeldOutMap map;
  std::string weights_sha256;
  Json adaptation;
};
SavedLedMap read_saved_led_map(const std::string& detect_dir);

struct LedCalibrationOptions {
  LedMaskOptions mask;            // the dilation count t is calibrated for (default the released code's 3)
  bool search_dilations = false;  // also choose the count, 0..kMaxCalibratedDilations
  bool search_peak = false;       // also choose the peak-relative rule
  // Only rules whose mean precision over the held-out datasets with drops reaches this count
  // (the target is 0.8 together with IoU 0.7); InputError when no rule of the grid does.
  std::optional<double> min_precision;
  void validate() const;
};
// Picks t on a grid 0.05..0.95 (step 0.025) maximizing the mean IoU over held-out datasets that have
// drops (datasets without drops only enter through precision: a false mask there lowers nothing in
// IoU, so they are reported, not optimized), for the mask options' dilation count, or with
// search_dilations over 0..3 dilations too. Ties go to fewer dilations, then to the smaller t. With
// search_peak, also the peak-relative rule (LedPeakRule) for the chosen dilations, on the grid
// kPeakGrid describes (ties go to the first in low, seed, fraction order).
LedCalibration calibrate_led(const std::vector<LedHeldOutMap>& held_out, const LedCalibrationOptions& options);
// The same on the network's maps of the held-out datasets.
LedCalibration calibrate_led(const LensDetector& led, const std::vector<std::string>& held_out, const LedMaskOptions& mask_options,
                             bool search_dilations = false, bool search_peak = false);
inline constexpr const char* kThresholdGrid = "0.05..0.95 step 0.025";
inline constexpr const char* kPeakGrid = "low 0.2..0.6 step 0.1 x seed low..0.7 step 0.1 x fraction 0.5..0.9 step 0.05";
// The calibration as stored in the weights' JSON ("calibration"); `grid` describes the t search.
Json calibration_json(const LedCalibration& c, const std::vector<std::string>& held_out, const std::string& grid);

struct TrainLedOptions {
  LedTrainOptions train;
  LedMaskOptions mask;  // the post-processing the calibration assumes (threshold is ignored; dilations
                        // default to the released code's 3)
  // Also choose the dilation count (0..3) on the held-out views. Off by default: the IoU-best count
  // (none) gave a higher mask IoU but worse WeatherGS reconstructions (docs/restoration_led.md).
  bool calibrate_dilations = false;
  // Also calibrate the peak-relative rule and store it with the weights (detect's default rule then).
  bool calibrate_peak = false;
  std::string command;  // the command line, recorded in the manifest
  // Start from these weights (their architecture and calibration) instead of a fresh network.
  std::string init;
  // A lens-fixed mask (PNG, 255 = leave out) applied to every training view: those pixels do not count
  // in the loss unless the view's own mask marks a drop there.
  std::string ignore_mask;
};
struct TrainLedResult {
  LedTrainRecord record;
  LedCalibration calibration;
  size_t examples = 0;
};
// Trains on every view of `train_datasets`, calibrates on `held_out`, writes <out_stem>.json/.bin
// (with the training record, the datasets, the calibration and the command).
TrainLedResult train_led(const std::vector<std::string>& train_datasets, const std::vector<std::string>& held_out,
                         const std::string& out_stem, const TrainLedOptions& options);

struct RecalibrateLedOptions {
  // Where the held-out maps come from, exactly one of: datasets the network runs on, or the outputs
  // of `detect --save-attention` made with these weights (read_saved_led_map).
  std::vector<std::string> held_out;
  std::vector<std::string> maps;
  // The maps were made with `detect --adapt`: calibrates the adapted peak rule only
  // (LensDetector::adapted_peak_rule, recorded as "adapted_calibration"); needs `maps`.
  bool adapted = false;
  bool search_peak = false;
  std::optional<double> min_precision;  // LedCalibrationOptions::min_precision
  // Run (and calibrate) the network at this internal width from then on; with held_out only.
  std::optional<int> width;
  std::string command;  // recorded with the calibration
  void validate() const;
};
// `weathergs calibrate-led`: calibrates trained weights again (threshold for the weights' dilation
// count, and the peak rule with search_peak; or with `adapted` the adapted peak rule) and writes them
// to out_stem: the same network (same blob and sha256), a new calibration; the previous one is kept as
// "previous_calibration" ("previous_adapted_calibration"). With `width`, the calibration records the
// width it had before as "width_changed_from".
LedCalibration recalibrate_led(const std::string& weights_stem, const std::string& out_stem, const RecalibrateLedOptions& options);

}  // namespace weathergs::restoration::led
