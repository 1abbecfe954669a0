// The learned Atmospheric Effect Filter (AEF) of WeatherGS (docs/restoration.md): two task plugins,
// `derain` and `desnow`, each a compact residual encoder-decoder trained by this project on the
// generator's pairs (the paper's Diff-Plugin on Stable Diffusion cannot be had or run here).
//
// It learns on top of the classical top-hat (particle_filter.h) rather than from nothing: per view,
// x = cat(RGB, the per-channel morphological opening of RGB, the white top-hat T of the luminance),
// all at full resolution (the opening is the top-hat's background estimate: a ready guess of what lies
// under a thin particle). A full-resolution conv, two stride-2 convs, dilated residual blocks at 1/4
// resolution and a U-Net decoder with skips emit two full-resolution maps: an alpha-logit correction c
// and a background correction delta. The particle alpha is a = sigmoid(g (T - t0) + c) (g (T - t0):
// the top-hat's own decision, softened) and the output is composited at full resolution,
//   restored = I + a * (B - I),  B = opening + delta,
// so where a = 0 the input pixel is kept exactly (a clear view costs nothing when a stays 0). Loss:
// (1 - w_ssim) L1 + w_ssim D-SSIM on the restored image against the no-particle target, plus
// w_alpha BCE of a against the particle mask.
//
// This header is free of libtorch: only aef_plugin.cc includes it. Weights: `<stem>.json` +
// `<stem>.bin` (restoration/torch_weights.h), as the LED's.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/json_reader.h"

namespace weathergs::restoration::aef {

inline constexpr const char* kAefFormat = "weathergs-aef";
inline constexpr int kAefFormatVersion = 1;

enum class AefPluginKind { kDerain, kDesnow };
const char* to_string(AefPluginKind k);  // "derain", "desnow"

struct AefArchitecture {
  int channels = 12;         // features at full resolution (2x at 1/2 resolution)
  int bottleneck = 32;       // features at 1/4 resolution
  int residual_blocks = 3;   // at 1/4 resolution, dilations 1, 2, 4, ...
  double opening_radius_px_at_300 = 2.0;  // disk of the input opening and top-hat, scaled with the width (the top-hat's)
  // The alpha prior: logit = prior_gain * (top-hat - prior_threshold) + the network's correction. The
  // untrained network is the classical filter (its threshold 0.05); gain 0 turns the prior off.
  double prior_threshold = 0.05;
  double prior_gain = 100;
  void validate() const;     // InputError naming the field
  int opening_radius_px(int width) const;
  Json to_json() const;
  static AefArchitecture from_json(const JsonReader& r);
};

struct AefTrainOptions {
  AefArchitecture arch;
  int iterations = 5000;
  int batch = 8;
  int crop = 96;                // random square crops (px) of the full-resolution views
  double learning_rate = 2e-3;  // Adam, cosine-decayed to 5%
  double ssim_weight = 0.2;     // (1 - w) L1 + w D-SSIM (3DGS's weighting)
  // Weight of the alpha BCE. Small: the particle masks mark every pixel a particle touches, also where
  // it changes the colour invisibly; 0.1 made the image terms lose (0.01: +4.0 dB vs 0.1: +3.9 dB on
  // market_w00 after 300 iterations, and a much lower image loss).
  double alpha_weight = 0.01;
  uint64_t seed = 1;
  int threads = 0;              // libtorch threads for training (0 = all cores)
  bool progress = true;
  void validate() const;        // InputError naming the field
};

// One training example: the weathered view (sRGB), its no-particle target (sRGB) and the particle
// mask (1 channel, 1 = particle), all the same size.
struct AefExample {
  Image image;
  Image target;
  Image alpha;
};

struct AefTrainRecord {
  std::vector<double> loss_curve;  // mean loss per 50 iterations
  double seconds = 0;
  int64_t parameters = 0;
};

struct AefOutput {
  Image restored;  // sRGB, 3 channels, the input's size
  Image alpha;     // 1 channel in [0, 1]: the particle alpha (mask mode thresholds it at 0.5)
};

class AefPlugin {
 public:
  AefPlugin(AefPluginKind kind, const AefArchitecture& arch, uint64_t seed);
  ~AefPlugin();
  AefPlugin(AefPlugin&&) noexcept;
  AefPlugin& operator=(AefPlugin&&) noexcept;

  // Reads `<stem>.json` + `<stem>.bin`; InputError naming the file and the fix when missing, corrupt,
  // of another format/version/architecture, or a plugin of another kind than `expected`.
  static AefPlugin load(const std::string& stem, AefPluginKind expected);
  void save(const std::string& stem, const Json& extra) const;

  AefPluginKind kind() const;
  const AefArchitecture& architecture() const;
  int64_t parameter_count() const;
  const Json& metadata() const;

  // Deterministic for a given seed and thread count (crops and flips keyed on (seed, iteration)).
  AefTrainRecord train(const std::vector<AefExample>& examples, const AefTrainOptions& options);
  // The training loss over whole examples (no update): tests check it decreases.
  double loss(const std::vector<AefExample>& examples, const AefTrainOptions& options) const;

  // `image`: sRGB, 3 or 4 channels (alpha ignored), at least 8x8; `where` names it in errors. Runs on
  // one libtorch thread (its 2-thread convolutions differ in the last bits); callable from several
  // threads at once (filter_dataset runs views in parallel), so outputs never depend on threads.
  AefOutput restore(const Image& image, const std::string& where) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace weathergs::restoration::aef
