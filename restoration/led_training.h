// Training and calibration of the Lens Effect Detector on generated datasets (docs/restoration_led.md,
// `weathergs train-led`, `make models`). libtorch-free.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "restoration/detect_dataset.h"
#include "restoration/lens_detector.h"

namespace weathergs::restoration {

// Every view of a dataset as (images/<view>.png, masks/lens/<view>.png); a dataset without masks/lens
// has no drops: its masks are zero.
std::vector<LedExample> read_led_examples(const std::string& dataset);

struct LedCalibration {
  double threshold = 0.5;
  int dilate_iterations = kReleasedCodeDilations;
  double mean_iou = 0;                  // over the held-out datasets with drops
  std::vector<LedScore> scores;         // at the chosen threshold and dilations
  // With search_peak: the peak-relative rule chosen for the same dilations, its mean IoU and scores.
  std::optional<LedPeakRule> peak;
  double peak_mean_iou = 0;
  std::vector<LedScore> peak_scores;
};
// The dilation counts a calibration with search_dilations tries: none up to the released code's three.
inline constexpr int kMaxCalibratedDilations = kReleasedCodeDilations;
// Picks t on a grid 0.05..0.95 (step 0.025) maximizing the mean IoU over held-out datasets that have
// drops (datasets without drops only enter through precision: a false mask there lowers nothing in
// IoU, so they are reported, not optimized), for mask_options' dilation count (default the released
// code's 3), or with search_dilations over 0..3 dilations too. Ties go to fewer dilations, then to the
// smaller t. With search_peak, also the peak-relative rule (LedPeakRule) for the chosen dilations,
// on the grid kPeakGrid describes (ties go to the first in low, seed, fraction order).
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

// `weathergs calibrate-led`: calibrates trained weights again on `held_out` (threshold for the weights'
// dilation count, and the peak rule with search_peak) and writes them to out_stem: the same network
// (same blob and sha256), a new calibration; the previous one is kept as "previous_calibration".
// With `width`, the network is run (and calibrated) at that internal width from then on; the
// calibration records the width it had before as "width_changed_from".
LedCalibration recalibrate_led(const std::string& weights_stem, const std::vector<std::string>& held_out,
                               const std::string& out_stem, bool search_peak, const std::string& command,
                               std::optional<int> width = std::nullopt);

}  // namespace weathergs::restoration
