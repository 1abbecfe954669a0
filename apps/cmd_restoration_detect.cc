// `weathergs detect`: the learned Lens Effect Detector over a dataset (docs/restoration_led.md).
#include <cstdio>
#include <fmt/format.h>
#include <memory>

#include "apps/command.h"
#include "apps/resources.h"
#include "core/parallel.h"
#include "restoration/led/detect_dataset.h"
#include "adaptation/led_adaptation.h"

namespace weathergs::cli {
namespace {

struct DetectArgs {
  std::string data, out, images, weights, rule;
  double threshold = 0;
  bool per_view = false;
  std::vector<double> band{0.5, 0.7};
  std::vector<double> peak;
  bool adapt = false;
  int adapt_iterations = 0;  // 0: from adapt_options.passes
  adaptation::LedAdaptOptions adapt_options;
  restoration::led::DetectDatasetOptions options;
};

std::string describe_rule(const restoration::led::LedMaskOptions& m) {
  switch (*m.rule) {
    case restoration::led::LedThresholdRule::kBand: return fmt::format("rule band [{:.3f}, {:.3f}]", m.band_lo, m.band_hi);
    case restoration::led::LedThresholdRule::kPeak:
      return fmt::format("rule peak (low {:.3f}, seed {:.3f}, fraction {:.3f})", m.peak->low, m.peak->seed, m.peak->fraction);
    default: return fmt::format("rule above t {:.3f}", *m.threshold);
  }
}

int run(DetectArgs& a) {
  a.options.weights = find_led_weights(a.weights);
  a.options.images_dir = a.images;
  a.options.averaging = a.per_view ? restoration::led::LedAveraging::kPerView : restoration::led::LedAveraging::kTrainViews;
  if (a.rule == "band") a.options.mask.rule = restoration::led::LedThresholdRule::kBand;
  if (a.rule == "above" || (a.rule.empty() && a.threshold > 0)) a.options.mask.rule = restoration::led::LedThresholdRule::kAbove;
  if (a.rule == "peak" || (a.rule.empty() && !a.peak.empty())) a.options.mask.rule = restoration::led::LedThresholdRule::kPeak;
  if (a.threshold > 0) a.options.mask.threshold = a.threshold;
  if (!a.peak.empty()) a.options.mask.peak = restoration::led::LedPeakRule{a.peak[0], a.peak[1], a.peak[2]};
  a.options.mask.band_lo = a.band[0];
  a.options.mask.band_hi = a.band[1];
  if (a.adapt) {
    if (a.adapt_iterations > 0) a.adapt_options.iterations = a.adapt_iterations;
    a.adapt_options.validate();
    a.options.adapt = adaptation::led_adaptation_hook(a.adapt_options);
  }
  const restoration::led::DetectDatasetReport r = restoration::led::detect_dataset(a.data, a.out, a.options);
  double mean = 0;
  for (const auto& v : r.views) mean += v.mask_fraction / double(r.views.size());
  std::printf("detected lens drops on %zu views in %.2f s (%.1f ms per view in the network), %s, %s, %d dilations: "
              "%.1f%% of the pixels masked on average\nwrote %s\n",
              r.views.size(), r.seconds, 1000 * r.seconds_per_view, restoration::led::to_string(a.options.averaging),
              describe_rule(r.mask).c_str(), *r.mask.dilate_iterations, 100 * mean, a.out.c_str());
  if (r.ground_truth)
    std::printf("against the dataset's masks/lens: IoU %.3f  precision %.3f  recall %.3f (drops on %.2f%% of the pixels)\n",
                r.ground_truth->iou, r.ground_truth->precision, r.ground_truth->recall, 100 * r.ground_truth->gt_fraction);
  if (r.coverage_truth)
    std::printf("against the drops' lens coverage >= %.2f: IoU %.3f  precision %.3f  recall %.3f (drops on %.2f%% of the pixels)\n",
                r.coverage_threshold, r.coverage_truth->iou, r.coverage_truth->precision, r.coverage_truth->recall,
                100 * r.coverage_truth->gt_fraction);
  return kExitOk;
}

Command make(CLI::App& root) {
  auto a = std::make_shared<DetectArgs>();
  CLI::App* sub = root.add_subcommand(
      "detect",
      "Find the drops on the lens in every view of a dataset with the learned Lens Effect Detector and write "
      "loss masks for 3DGS (255 = excluded; docs/restoration_led.md).");
  sub->add_option("--data", a->data, "Dataset folder")->required();
  sub->add_option("--out", a->out, "Output folder: <view>.png masks and detect.json")->required();
  sub->add_option("--images", a->images, "Detect on these <view>.png instead of the dataset's images/ (e.g. `filter` output)");
  sub->add_option("--weights", a->weights,
                  "Weights stem (<stem>.json + <stem>.bin); default $WEATHERGS_LED_WEIGHTS, else the installed models/led/led");
  sub->add_flag("--per-view", a->per_view,
                "Each view's own attention (drops on a window, sliding drops) instead of the mean over the training views");
  CLI::Option* threshold = sub->add_option("--threshold", a->threshold, "Mask where the attention >= t (default: the weights' calibrated t; implies --rule above)")
      ->check(CLI::Range(0.0, 1.0));
  sub->add_option("--rule", a->rule,
                  "above: attention >= t (the paper); band: lo <= attention <= hi (the released code); peak: per drop, "
                  ">= fraction x its peak (default: peak when the weights store a calibrated peak rule, else above)")
      ->check(CLI::IsMember({"above", "band", "peak"}));
  sub->add_option("--peak", a->peak, "LOW SEED FRACTION of --rule peak (default: the weights' calibrated ones; implies --rule peak)")
      ->expected(3)
      ->excludes(threshold);
  sub->add_option("--band", a->band, "The band of --rule band")->expected(2)->capture_default_str();
  sub->add_option("--dilate", a->options.mask.dilate_iterations,
                  "3x3 dilations of the mask (default: the weights' calibrated count; 3 with --rule band)")
      ->check(CLI::Range(0, restoration::led::kMaxDilations));
  sub->add_flag("--save-attention", a->options.save_attention,
                "Also write the soft attention behind each mask as attention/<view>.png (16-bit, value = attention)");
  CLI::Option* adapt =
      sub->add_flag("--adapt", a->adapt,
                    "Adapt the network to this scene first: fine-tune a copy on the training views with new lens "
                    "drops rendered over them (~31 s on 2 cores for a quick-profile dataset, ~50 s at the paper "
                    "profile), then cut its map with the weights' adapted peak rule when they store one "
                    "(docs/record/led_adaptation.md)");
  CLI::Option* passes =
      sub->add_option("--adapt-passes", a->adapt_options.passes,
                      "Length of --adapt's fine-tune, in passes over its layouts x training views examples (the "
                      "default makes 100 iterations for 14 training views, 207 for 29; docs/record/led_adaptation.md, "
                      "\"Scaled with the training views\")")
          ->capture_default_str()
          ->needs(adapt);
  sub->add_option("--adapt-iterations", a->adapt_iterations,
                  "A fixed iteration count for --adapt's fine-tune instead of --adapt-passes (30 on a 14-view "
                  "dataset: ~3x sooner than the default 100, IoU ~0.005 lower on the validation scenes; "
                  "docs/record/led_adaptation.md, \"Fewer still\")")
      ->check(CLI::Range(1, adaptation::kMaxAdaptIterations))
      ->excludes(passes)
      ->needs(adapt);
  sub->add_option("--adapt-layouts", a->adapt_options.layouts, "Drop layouts rendered over every training view by --adapt")
      ->capture_default_str()
      ->needs(adapt);
  return {sub, [a] {
            a->adapt_options.threads = num_threads();
            return run(*a);
          }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(detect, weathergs::cli::make)
