// The learned Lens Effect Detector (LED) of WeatherGS (docs/restoration_led.md): the attentive-recurrent
// network of AttentiveGAN (Qian et al., CVPR 2018), shrunk to run on 2 CPU cores. Each of N recurrent
// steps takes cat(RGB, sharpness, previous attention), runs a strided conv, dilated residual blocks and a ConvLSTM,
// and emits a 1-channel sigmoid attention map; the first attention is 0.5. Trained on the generator's
// lens masks with the loss sum_t theta^(N-t) * MSE(A_t, M), theta = 0.8 (the paper's values).
//
// This header is free of libtorch: only lens_detector.cc includes <torch/torch.h>. Weights live in
// two files, `<stem>.json` (architecture, parameter table, calibrated threshold, sha256 of the blob,
// training record) and `<stem>.bin` (little-endian float32 parameters in table order).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/json_reader.h"

namespace weathergs::restoration::led {

inline constexpr const char* kLedFormat = "weathergs-led";
inline constexpr int kLedFormatVersion = 1;
// The released code's 3x3 dilations of the LED mask (three): the default count a threshold is
// calibrated for, the band preset's, and the one of weights saved before the count was stored.
inline constexpr int kReleasedCodeDilations = 3;
// The most 3x3 dilations any option or weights file may ask for (a 101-pixel square per drop pixel).
inline constexpr int kMaxDilations = 50;
// n when 0 <= n <= kMaxDilations, else an InputError naming the LED's dilate_iterations.
int checked_dilations(int n);

// What the views of one network call share (docs/record/led_variants.md, "Pooling over the views";
// measured, not adopted):
// kNone: every view on its own (the paper's network). kAttention: each recurrent step also sees the
// mean of the previous attention over the views of the call. kAttentionAndState: and the ConvLSTM sees
// the mean of its hidden state over them. A lens-fixed drop sits at the same place in every view, the
// scene and the falling particles do not. A pooled network must be run on the views of one dataset
// together (detect does), and is trained on batches of views of one dataset.
enum class LedViewPooling { kNone, kAttention, kAttentionAndState };
const char* to_string(LedViewPooling p);
LedViewPooling parse_led_view_pooling(const std::string& s, const std::string& where);

struct LedArchitecture {
  int steps = 4;           // recurrent steps (the paper's N)
  int width = 216;         // internal width in pixels; the height keeps the aspect ratio
  int channels = 16;       // feature channels after the strided conv (and of the ConvLSTM state)
  int residual_blocks = 3; // dilations 1, 2, 4, ... (the receptive field must cover a defocused drop)
  LedViewPooling view_pooling = LedViewPooling::kNone;  // `view_pooling` in the JSON (absent: none)
  void validate() const;   // InputError naming the field
  Json to_json() const;
  static LedArchitecture from_json(const JsonReader& r);
};

// The peak-relative threshold of the averaged attention (docs/record/led_history.md, "The peak-relative
// rule"): every 8-connected region where m >= low whose maximum reaches seed keeps its pixels with
// m >= max(low, fraction * maximum); regions whose maximum stays under seed are dropped. The network is
// less sure of medium drops than of large ones (their peaks are lower), so one global threshold
// segments them smaller or not at all; a level relative to each drop's own peak does not depend on it.
// The defaults (used by `detect --rule peak` on weights without a calibrated rule) are the shipped
// weights' calibration.
struct LedPeakRule {
  double low = 0.3;
  double seed = 0.3;
  double fraction = 0.7;
  void validate() const;  // 0 < low <= seed < 1, 0 < fraction <= 1
  Json to_json() const;
  static LedPeakRule from_json(const JsonReader& r);
};

// The largest per-pixel weight of the drop-size balance (LedTrainOptions::drop_balance_area).
inline constexpr double kMaxDropWeight = 4.0;

// How a training batch's gradient is computed.
// kBatched: one forward and backward pass over the stacked batch with `threads` libtorch intra-op
//   threads (the shipped weights' recipe; the weights depend on the thread count in their last bits).
// kPerExample: each example's share of the batch loss is differentiated on its own with one intra-op
//   thread, `threads` examples at a time, and the shares' gradients are summed in batch order: the
//   same weights whatever the thread count (the test-time adaptation, adaptation/led_adaptation). Not for
//   view-pooling networks, whose examples are one forward pass.
enum class LedGradient { kBatched, kPerExample };
const char* to_string(LedGradient g);  // "batched", "per-example"

struct LedTrainOptions {
  LedArchitecture arch;
  int iterations = 4500;
  int batch = 4;
  double learning_rate = 2e-3;  // Adam; cosine-decayed to 5% over the run
  double theta = 0.8;           // weight of step t is theta^(N-t)
  // Photometric augmentation, in [0, 0.5]: each drawn example's RGB channels are scaled by gains
  // uniform in [1 - j, 1 + j], times an overall gain from the same range that also scales the
  // sharpness channel (values clamped to [0, 1]). 0 = off (no draws), as for the shipped LED.
  double colour_jitter = 0;
  // Drop-size balance of the attention loss, in internal pixels (0 = off: the paper's plain MSE).
  // With R > 0 every pixel of a ground-truth drop (a connected region of the mask at the internal
  // size) of area A < R weighs sqrt(R / A), at most kMaxDropWeight, all other pixels 1, and the
  // loss is the weighted mean: small and medium drops count per drop more like the large ones do.
  double drop_balance_area = 0;
  uint64_t seed = 1;
  int threads = 0;              // 0 = all cores (libtorch intra-op threads, or examples at a time)
  LedGradient gradient = LedGradient::kBatched;
  bool progress = true;
  void validate() const;
};

// One training example: an sRGB view (3 channels) and its lens mask (1 channel, 1 = drop), same size.
struct LedExample {
  Image image;
  Image mask;
  int group = 0;  // the dataset it comes from: a view-pooling network trains on one group per batch
  // Optional per-pixel loss weight in [0, 1] (1 channel, the image's size; empty = 1 everywhere):
  // test-time adaptation leaves the scene's own, unlabelled drops out of the loss with it.
  Image weight{};
};

struct LedTrainRecord {
  std::vector<double> loss_curve;  // mean loss per 50 iterations
  double seconds = 0;
  int64_t parameters = 0;
};

class LensDetector {
 public:
  // A freshly initialized network (weights from `seed`).
  LensDetector(const LedArchitecture& arch, uint64_t seed);
  ~LensDetector();
  LensDetector(LensDetector&&) noexcept;
  LensDetector& operator=(LensDetector&&) noexcept;

  // Reads `<stem>.json` + `<stem>.bin`. InputError naming the file and the fix when either is missing,
  // corrupt (sha256), of another format or version, or its table does not match the architecture.
  static LensDetector load(const std::string& stem);
  // Writes both files atomically; `extra` (training record, calibration, ...) is merged into the JSON.
  void save(const std::string& stem, const Json& extra) const;

  // An independent copy (parameters, calibration, metadata): test-time adaptation trains the copy.
  LensDetector clone() const;

  const LedArchitecture& architecture() const;
  // Runs the same network at another internal width (no parameter depends on it; a larger width
  // enlarges every drop inside the network; docs/record/led_variants.md, "Run at width 252").
  // InputError outside 16..2048.
  void set_width(int width);
  int64_t parameter_count() const;
  // The calibrated threshold stored with the weights (0.5 until calibrated).
  double threshold() const;
  void set_threshold(double t);
  // The number of 3x3 dilations after the threshold that the threshold was calibrated for
  // (kReleasedCodeDilations for weights saved before the count was stored).
  int dilate_iterations() const;
  void set_dilate_iterations(int n);
  // The calibrated peak-relative rule stored with the weights (`peak_rule` in <stem>.json), if any;
  // `weathergs detect` uses it by default when present (docs/restoration_led.md).
  const std::optional<LedPeakRule>& peak_rule() const;
  void set_peak_rule(const std::optional<LedPeakRule>& rule);
  // The peak rule calibrated on maps of this network adapted to each held-out scene (`adapted_peak_rule`
  // in <stem>.json; `calibrate-led --maps ... --adapted`), if any: `detect --adapt` uses it instead of
  // peak_rule(), since the adapted network's maps peak differently (docs/record/led_adaptation.md).
  const std::optional<LedPeakRule>& adapted_peak_rule() const;
  void set_adapted_peak_rule(const std::optional<LedPeakRule>& rule);
  const Json& metadata() const;  // the JSON read by load (empty for a fresh network)

  // Trains in place on `examples` (resized to the internal width once, up front). Deterministic for a
  // given seed and thread count.
  LedTrainRecord train(const std::vector<LedExample>& examples, const LedTrainOptions& options);

  // The mean of the N attention maps, bilinearly resized to the image's size, in [0, 1]. `image`:
  // sRGB, 3 or 4 channels (alpha ignored); `where` names it in errors. Runs on one libtorch thread
  // whatever --threads says (faster for this small network; bench_restoration).
  Image attention(const Image& image, const std::string& where) const;
  // Attention for several images at once (same size), one batch: faster than one by one.
  std::vector<Image> attention(const std::vector<Image>& images, const std::string& where) const;

  // The training loss of one batch (no update): tests check it decreases.
  double loss(const std::vector<LedExample>& examples, double theta) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  explicit LensDetector(std::unique_ptr<Impl> impl);
};

}  // namespace weathergs::restoration::led
