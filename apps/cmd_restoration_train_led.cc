// `weathergs train-led`: trains and calibrates the Lens Effect Detector (docs/restoration_led.md, make models).
#include <cstdio>
#include <memory>

#include "apps/command.h"
#include "apps/led_scores.h"
#include "restoration/led/led_training.h"

namespace weathergs::cli {
namespace {

struct TrainLedArgs {
  std::vector<std::string> data, held_out;
  std::string out;
  restoration::led::TrainLedOptions options;
  std::string view_pooling = "none";
  std::string command;
};

int run(TrainLedArgs& a) {
  a.options.command = a.command;
  a.options.train.arch.view_pooling = restoration::led::parse_led_view_pooling(a.view_pooling, "--view-pooling");
  const restoration::led::TrainLedResult r = restoration::led::train_led(a.data, a.held_out, a.out, a.options);
  std::printf("trained the LED on %zu views (%lld parameters) in %.1f s; loss %.4f -> %.4f\n", r.examples,
              static_cast<long long>(r.record.parameters), r.record.seconds,
              r.record.loss_curve.empty() ? 0.0 : r.record.loss_curve.front(),
              r.record.loss_curve.empty() ? 0.0 : r.record.loss_curve.back());
  if (!a.held_out.empty()) {
    std::printf("calibrated threshold %.3f and %d dilations: mean IoU %.3f over held-out datasets with drops\n",
                r.calibration.threshold, r.calibration.dilate_iterations, r.calibration.mean_iou);
    print_led_scores(r.calibration.scores);
    if (r.calibration.peak) {
      const restoration::led::LedPeakRule& p = *r.calibration.peak;
      std::printf("calibrated peak rule (low %.2f, seed %.2f, fraction %.2f): mean IoU %.3f\n", p.low, p.seed, p.fraction,
                  r.calibration.peak_mean_iou);
      print_led_scores(r.calibration.peak_scores);
    }
  }
  std::printf("wrote %s.json and %s.bin\n", a.out.c_str(), a.out.c_str());
  return kExitOk;
}

Command make(CLI::App& root) {
  auto a = std::make_shared<TrainLedArgs>();
  CLI::App* sub = root.add_subcommand(
      "train-led",
      "Train the Lens Effect Detector on generated datasets (images/ + masks/lens/) and calibrate its threshold on "
      "held-out ones (docs/restoration_led.md; `make models` runs the documented recipe).");
  sub->add_option("--data", a->data, "Training datasets")->required();
  sub->add_option("--held-out", a->held_out, "Held-out datasets for the threshold calibration (never trained on)");
  sub->add_option("--out", a->out, "Weights stem: writes <stem>.json and <stem>.bin")->required();
  auto& t = a->options.train;
  sub->add_option("--iterations", t.iterations, "Training iterations")->capture_default_str();
  sub->add_option("--batch", t.batch, "Views per iteration")->capture_default_str();
  sub->add_option("--learning-rate", t.learning_rate, "Adam learning rate (cosine-decayed to 5%)")->capture_default_str();
  sub->add_option("--seed", t.seed, "Seed of the initialization and of the batch order")->capture_default_str();
  sub->add_option("--threads", t.threads, "libtorch threads (0 = all cores)")->capture_default_str();
  sub->add_option("--width", t.arch.width, "Internal width in pixels")->capture_default_str();
  sub->add_option("--channels", t.arch.channels, "Feature channels")->capture_default_str();
  sub->add_option("--steps", t.arch.steps, "Recurrent steps")->capture_default_str();
  sub->add_option("--view-pooling", a->view_pooling,
                  "What the views of one dataset share: none (each view alone), attention (the mean previous attention) "
                  "or attention+state (and the ConvLSTM's mean state); pooled networks train on --batch views of one dataset "
                  "(measured, not adopted: docs/record/led_variants.md, \"Pooling over the views\")")
      ->check(CLI::IsMember({"none", "attention", "attention+state"}))
      ->capture_default_str();
  CLI::Option* dilate = sub->add_option("--dilate", a->options.mask.dilate_iterations,
                                        "3x3 dilations the threshold is calibrated for and stored with (default 3, the released code's)")
                            ->check(CLI::Range(0, restoration::led::kMaxDilations));
  sub->add_flag("--calibrate-dilation", a->options.calibrate_dilations,
                "Choose the dilations (0..3) with the threshold for the held-out mask IoU (higher IoU, worse reconstructions: "
                "docs/restoration_led.md)")
      ->excludes(dilate);
  sub->add_flag("--calibrate-peak", a->options.calibrate_peak,
                "Also calibrate the peak-relative rule (per drop, attention >= fraction x its peak) and store it with the "
                "weights: `detect` then uses it by default (docs/restoration_led.md)");
  sub->add_option("--colour-jitter", t.colour_jitter, "Photometric augmentation: channel and overall gains in [1-j, 1+j] (0 = off)")
      ->capture_default_str();
  sub->add_option("--balance-drops", t.drop_balance_area,
                  "Drop-size balance of the loss: pixels of a drop smaller than this many internal pixels weigh "
                  "sqrt(R / area), at most 4 (0 = off, the paper's plain MSE)")
      ->check(CLI::Range(0.0, 1e6))
      ->capture_default_str();
  sub->add_option("--init", a->options.init, "Start from these weights (architecture, calibration) instead of a fresh network");
  sub->add_option("--ignore-mask", a->options.ignore_mask,
                  "Mask PNG (255 = leave out of the loss unless the view's own mask marks a drop), for every view");
  return {sub, [a, sub] {
            a->command = recorded_command("train-led", *sub);
            return run(*a);
          }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(train_led, weathergs::cli::make)
