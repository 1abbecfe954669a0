// `weathergs detect`: the learned Lens Effect Detector over the views of a dataset, turned into loss
// masks for 3DGS (docs/restoration_led.md). libtorch-free: the network is behind restoration/led/lens_detector.h.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/dataset.h"
#include "core/image.h"
#include "core/json_reader.h"
#include "core/stage_output.h"
#include "restoration/led/lens_detector.h"

namespace weathergs::restoration::led {

inline constexpr const char* kDetectReportFile = "detect.json";  // written last: the output is complete
// detect.json's keys, spelled once: detect_dataset writes them; detect_output, read_detect_record and
// read_saved_led_map (led_training.h) read them. The settings that decide the masks
// (detect_settings_json) are weights_sha256, images, averaging, rule, threshold, band, peak_rule and
// dilate_iterations; ground_truth and ground_truth_coverage hold a score (kScore*).
namespace detect_key {
inline constexpr const char* kFormat = "format";  // kDetectFormat
inline constexpr const char* kVersion = "version";
inline constexpr const char* kDataset = "dataset";
inline constexpr const char* kWeights = "weights";
inline constexpr const char* kWeightsSha256 = "weights_sha256";
inline constexpr const char* kImages = "images";
inline constexpr const char* kAveraging = "averaging";
inline constexpr const char* kRule = "rule";
inline constexpr const char* kThreshold = "threshold";
inline constexpr const char* kBand = "band";
inline constexpr const char* kPeakRule = "peak_rule";
inline constexpr const char* kDilateIterations = "dilate_iterations";
inline constexpr const char* kAdaptation = "adaptation";
inline constexpr const char* kAveragedViews = "averaged_views";
inline constexpr const char* kAttention = "attention";
inline constexpr const char* kGroundTruth = "ground_truth";
inline constexpr const char* kGroundTruthCoverage = "ground_truth_coverage";
inline constexpr const char* kSeconds = "seconds";
inline constexpr const char* kSecondsPerView = "seconds_per_view";
inline constexpr const char* kViews = "views";  // per view: kView, kMaskFraction, kMeanAttention
inline constexpr const char* kView = "view";
inline constexpr const char* kMeanAttention = "mean_attention";
// A score (LedScore) against the dataset's truth: which masks, over how many views, and the counts.
inline constexpr const char* kScoreMasks = "masks";
inline constexpr const char* kScoreViews = "views";
inline constexpr const char* kScoreIou = "iou";
inline constexpr const char* kScorePrecision = "precision";
inline constexpr const char* kScoreRecall = "recall";
inline constexpr const char* kGtFraction = "gt_fraction";
inline constexpr const char* kMaskFraction = "mask_fraction";
}  // namespace detect_key
inline constexpr const char* kDetectFormat = "weathergs-detect";
// With save_attention: the soft attention each mask was thresholded from, <out>/attention/<view>.png
// (16-bit, value = attention in [0, 1]), for choosing a threshold without rerunning the network.
inline constexpr const char* kDetectAttentionDir = "attention";
// The weights shipped with the repository (models/README.md), relative to the source tree.
inline constexpr const char* kDefaultLedWeights = "models/led/led";

// kTrainViews: one mask from the attention averaged over the training views only (the paper's
// "enhanced with averaging", for drops fixed to the lens), written for every view. kPerView: each
// view's own attention (drops on a window, or sliding).
enum class LedAveraging { kTrainViews, kPerView };
const char* to_string(LedAveraging a);

// How the averaged attention becomes a mask. kAbove: m >= t (the paper's M = 1(C >= t)). kBand: the
// released code's interactive band lo <= m <= hi, default [0.5, 0.7] (a named preset, not our default).
// kPeak: per drop, a level relative to its own peak (LedPeakRule, lens_detector.h).
enum class LedThresholdRule { kAbove, kBand, kPeak };
const char* to_string(LedThresholdRule r);

struct LedMaskOptions {
  // Default: kPeak when the weights store a calibrated peak rule, else kAbove.
  std::optional<LedThresholdRule> rule;
  std::optional<double> threshold;   // kAbove; default: the weights' calibrated threshold
  double band_lo = 0.5, band_hi = 0.7;  // kBand
  std::optional<LedPeakRule> peak;   // kPeak; default: the weights' calibrated rule, else LedPeakRule{}
  // 3x3 dilations of the thresholded mask. Default: the weights' count (the one their t or peak rule
  // was calibrated for) with kAbove and kPeak, kReleasedCodeDilations with kBand (the released code's preset).
  std::optional<int> dilate_iterations;
  void validate() const;
  // Every optional filled in from the weights as documented above.
  LedMaskOptions resolved(const LensDetector& led) const;
};

// Attention -> {0, 1} mask by `options` (resolved: rule, threshold, peak and dilations set), then
// its 3x3 dilations.
Image attention_to_mask(const Image& attention, const LedMaskOptions& options);

// A predicted mask against ground-truth lens masks, pixel counts summed over the views (one IoU for
// the set). A set without drops and without a prediction scores IoU 1.
struct LedScore {
  std::string dataset;
  double iou = 0, precision = 0, recall = 0;
  double gt_fraction = 0, mask_fraction = 0;  // of the pixels, over the views
};
LedScore score_lens_masks(const std::string& name, const std::vector<Image>& predicted, const std::vector<Image>& truth);

// Test-time adaptation of the network to the dataset before it runs (adaptation/led_adaptation.h supplies
// one: restoration cannot render drops). Gets the loaded network, the dataset and its training views
// as read (names and images, dataset order); returns the network to run and fills `report`, which
// detect.json stores as "adaptation".
using LedAdaptation = std::function<LensDetector(const LensDetector& base, const Dataset& dataset,
                                                 const std::vector<std::string>& views,
                                                 const std::vector<Image>& images, Json& report)>;

struct DetectDatasetOptions {
  std::string weights = kDefaultLedWeights;  // stem of <stem>.json + <stem>.bin
  std::string images_dir;  // detect on these <view>.png instead of the dataset's images/ (e.g. AEF output)
  LedAveraging averaging = LedAveraging::kTrainViews;
  LedMaskOptions mask;
  int batch = 1;           // views per network call (batches of 4 measured slower per view)
  bool save_attention = false;  // also write <out>/attention/<view>.png (kDetectAttentionDir)
  LedAdaptation adapt;     // empty: the weights as they are. Needs kTrainViews averaging.
};

struct DetectViewReport {
  std::string view;
  double mask_fraction = 0;
  double mean_attention = 0;
};
struct DetectDatasetReport {
  std::vector<DetectViewReport> views;  // dataset order
  LedMaskOptions mask;                  // the post-processing used, resolved
  double seconds = 0;
  double seconds_per_view = 0;          // network time only
  std::optional<LedScore> ground_truth; // when the dataset has masks/lens: over the averaged views
                                        // (train views), or every view with per-view averaging
  // Against where the drops are rather than where they show: the lens coverage layer at or above
  // the dataset's coverage-rule threshold (its resolved lens_droplets.mask_threshold), over the same
  // views, when the dataset has layers/lens_coverage/ for all of them (docs/record/led_targets.md,
  // "Where the drops are, not where they show").
  std::optional<LedScore> coverage_truth;
  double coverage_threshold = 0;
};

// The keys of detect.json that decide its masks, apart from the adaptation (whose report the adapt
// hook writes): the weights' sha256, the images, the averaging and the post-processing `resolved`
// (LedMaskOptions::resolved). detect_dataset writes them; a run that resumes compares them with
// settings_mismatch (core/json_reader.h) instead of detecting again (methods/reconstruct).
Json detect_settings_json(const std::string& weights_sha256, const DetectDatasetOptions& options,
                          const LedMaskOptions& resolved);

// An adapted network's maps peak differently from the base's: they are cut with the rule the weights
// store for adapted maps (`adapted_peak_rule`, calibrate-led --adapted) when they have one. Sets
// `led`'s peak rule to it; leaves `led` as it is otherwise.
void use_adapted_peak_rule(LensDetector& led);

// What `out` holds against `options`: complete when its detect.json records the same masks, stale
// naming the first difference, absent without detect.json (written last). `adaptation`: the settings
// record of the adaptation this run asks for (null: the weights as they are), compared with
// detect.json's "adaptation".
StageOutput detect_output(const std::string& out, const DetectDatasetOptions& options, const Json& adaptation);

// Writes <out>/<view>.png for every view (255 = excluded from the loss, the dataset's mask convention)
// and detect.json last, atomically. InputError names the dataset, view, weights or option.
DetectDatasetReport detect_dataset(const std::string& dataset, const std::string& out, const DetectDatasetOptions& options);

// What a finished detect.json tells the layers above (methods/: the cost, the weights, the warning).
struct DetectRecord {
  double seconds = 0;               // the whole detection, adaptation included
  std::string weights_sha256;
  std::optional<LedScore> ground_truth;  // against masks/lens, when the dataset has them
};
// Reads <out>/detect.json as detect_dataset writes it; InputError naming the file and key.
DetectRecord read_detect_record(const std::string& out);

// A LED that fails silently: where the dataset's ground-truth drops cover at least
// kSilentLedTruthFraction of the scored views' pixels and the masks cover less than
// kSilentLedMaskShare of what they do, the warning to show (naming both fractions); empty otherwise,
// and for a record without ground truth.
inline constexpr double kSilentLedTruthFraction = 0.1;  // "a tenth or more of the views"
inline constexpr double kSilentLedMaskShare = 0.01;     // a hundredth of the truth: "masks nothing"
std::string silent_led_warning(const DetectRecord& record);

// The mean attention of `views` (sRGB images of one size): the averaging step on its own (calibration).
Image mean_attention(const LensDetector& led, const std::vector<Image>& views, const std::string& where, int batch = 1);

}  // namespace weathergs::restoration::led
