// Test-time adaptation of the Lens Effect Detector to one scene (docs/restoration_led.md, "Adapted to
// the scene"). The shipped LED carries over to a scene it has not seen less well than to one it was
// trained on (restoration_led_targets.md, "The network meets the targets on scenes it has seen"). This
// fine-tunes a copy of it on the scene's own training views with new lens drops rendered over them by
// the generator's lens model: the new drops' masks are exact, and the scene's own drops (unlabelled:
// no method knows where they are) are left out of the loss where the base network's averaged map
// reaches `ignore_level`. No ground truth of the scene is used. Lives in methods/ because it needs both
// the generator (drops) and restoration (the network); `weathergs detect --adapt` and the WeatherGS
// recipes' `--led-adapt` run it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/dataset.h"
#include "core/image.h"
#include "core/json_reader.h"
#include "restoration/led/detect_dataset.h"
#include "restoration/led/lens_detector.h"

namespace weathergs::adaptation {

struct LedAdaptOptions {
  // Drop layouts rendered over every training view. Layout k (0-based) follows the LED training
  // set's recipe (scripts/make-training-data.sh: radius 0.3-1.5 mm, glass at 15 mm), with the style
  // and count of kAdaptLayouts[k % 4] and weather seed kAdaptSeedBase + k + 1.
  int layouts = 4;
  // How long the fine-tune runs: `passes` over its layouts x training views examples, in whole
  // iterations of `batch` (fine_tune_iterations), unless `iterations` fixes the count. 400/56 passes
  // make 100 iterations on a quick-profile dataset (14 training views, 56 examples), where 100 scored
  // as 300 did (docs/record/led_adaptation.md, "Fewer iterations"), and 207 on a paper-profile one
  // (29 views), where a fixed 100 scored ~0.01 IoU under 300 ("Scaled with the training views").
  double passes = 400.0 / 56.0;
  std::optional<int> iterations;
  double learning_rate = 5e-4;  // a quarter of the training recipe's 2e-3: a fine-tune, not a new network
  int batch = 4;
  // The base network's averaged attention at or above this level, dilated ignore_dilations times
  // (3x3 cross), is left out of the loss unless a new drop covers the pixel.
  double ignore_level = 0.2;
  int ignore_dilations = 3;
  uint64_t seed = 1;   // batch order and flips
  int threads = 0;     // libtorch threads of the fine-tune (0 = all cores)
  bool progress = true;
  void validate() const;  // InputError naming the option
  // The fine-tune's iterations for `train_views` training views: `iterations` when set, else
  // round(passes * layouts * train_views / batch), at least 1.
  int fine_tune_iterations(size_t train_views) const;
};

struct LedAdaptLayout {
  const char* style;  // "paper" or "physical" (generator styles, docs/formats.md)
  int count;          // drops on the glass
};
inline constexpr LedAdaptLayout kAdaptLayouts[4] = {{"physical", 40}, {"paper", 30}, {"physical", 50}, {"paper", 20}};
inline constexpr uint64_t kAdaptSeedBase = 9000;
// The largest layouts and iterations LedAdaptOptions accepts (the commands check their flags with them).
inline constexpr int kMaxAdaptLayouts = 64;
inline constexpr int kMaxAdaptIterations = 100000;
// The fine-tune's gradient: per example, so the adapted network does not depend on the thread count.
inline constexpr restoration::led::LedGradient kAdaptGradient = restoration::led::LedGradient::kPerExample;
inline constexpr double kAdaptRadiusMm[2] = {0.3, 1.5};
inline constexpr double kAdaptGlassDistanceM = 0.015;

// The weather spec of layout k (0-based): {"seed", "style", "effects": {"lens_droplets": {...}}}.
Json adapt_layout_spec(int k);

// The copy of `base` fine-tuned on `images` (sRGB, the training views `views` of `dataset`, in dataset
// order). `report` gets the options, the layouts, the ignored fraction, the loss and the seconds.
// The same network whatever the thread count (restoration::led::LedGradient::kPerExample).
restoration::led::LensDetector adapt_led(const restoration::led::LensDetector& base, const Dataset& dataset,
                                    const std::vector<std::string>& views, const std::vector<Image>& images,
                                    const LedAdaptOptions& options, Json& report);

// The options that decide the adapted network of a dataset with `train_views` training views, as
// adapt_led's report holds them (the iteration count resolved, so `passes` and a fixed count that
// agree are the same request), and its gradient mode (per-example, so the thread count does not
// change the network and is not among them). A run that resumes compares them with
// settings_mismatch (core/json_reader.h; methods/reconstruct).
Json adaptation_settings_json(const LedAdaptOptions& options, size_t train_views);

// adapt_led with `options` as restoration::led::detect_dataset's adapt hook (`detect --adapt`,
// `reconstruct --led-adapt`).
restoration::led::LedAdaptation led_adaptation_hook(const LedAdaptOptions& options);

}  // namespace weathergs::adaptation
