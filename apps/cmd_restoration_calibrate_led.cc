// `weathergs calibrate-led`: calibrates trained LED weights again on held-out datasets (docs/restoration_led.md).
#include <cstdio>
#include <memory>
#include <optional>

#include "apps/command.h"
#include "apps/led_scores.h"
#include "apps/resources.h"
#include "restoration/led/led_training.h"

namespace weathergs::cli {
namespace {

struct CalibrateLedArgs {
  std::string weights, out;
  restoration::led::RecalibrateLedOptions options;
};

int run(const CalibrateLedArgs& a) {
  const std::string weights = find_led_weights(a.weights);
  const restoration::led::LedCalibration c = restoration::led::recalibrate_led(weights, a.out, a.options);
  if (!a.options.adapted) {
    std::printf("calibrated threshold %.3f for %d dilations: mean IoU %.3f, precision %.3f over held-out datasets with drops\n",
                c.threshold, c.dilate_iterations, c.mean_iou, c.mean_precision);
    print_led_scores(c.scores);
  }
  if (c.peak) {
    std::printf("calibrated %speak rule (low %.2f, seed %.2f, fraction %.2f): mean IoU %.3f, precision %.3f\n",
                a.options.adapted ? "adapted " : "", c.peak->low, c.peak->seed, c.peak->fraction, c.peak_mean_iou,
                c.peak_mean_precision);
    print_led_scores(c.peak_scores);
  }
  std::printf("wrote %s.json and %s.bin (the network of %s, recalibrated)\n", a.out.c_str(), a.out.c_str(), weights.c_str());
  return kExitOk;
}

Command make(CLI::App& root) {
  auto a = std::make_shared<CalibrateLedArgs>();
  CLI::App* sub = root.add_subcommand(
      "calibrate-led",
      "Calibrate trained Lens Effect Detector weights again on held-out datasets: the threshold for their dilation "
      "count and, with --peak, the peak-relative rule; writes the same network with the new calibration "
      "(docs/restoration_led.md).");
  sub->add_option("--weights", a->weights,
                  "Weights stem to calibrate; default $WEATHERGS_LED_WEIGHTS, else the installed models/led/led");
  sub->add_option("--held-out", a->options.held_out, "Held-out datasets with masks/lens (never trained on): the network runs on them");
  sub->add_option("--maps", a->options.maps,
                  "Instead of --held-out: outputs of `weathergs detect --save-attention` made with these weights on held-out "
                  "datasets (their detect.json names the dataset)");
  sub->add_option("--out", a->out, "Output weights stem: writes <stem>.json and <stem>.bin")->required();
  sub->add_flag("--peak", a->options.search_peak, "Also calibrate the peak-relative rule and store it (detect's default rule then)");
  sub->add_flag("--adapted", a->options.adapted,
                "The --maps were made with `detect --adapt`: calibrate only the rule `detect --adapt` uses "
                "(adapted_peak_rule; needs --peak; docs/record/led_adaptation.md)");
  sub->add_option("--min-precision", a->options.min_precision,
                  "Only rules whose mean held-out precision reaches this (0..1; default: no bound, the highest mean IoU)");
  sub->add_option("--width", a->options.width,
                  "Run the same network at this internal width from now on (16..2048 px; default: the weights' own)");
  return {sub, [a, sub] {
            a->options.command = recorded_command("calibrate-led", *sub);
            return run(*a);
          }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(calibrate_led, weathergs::cli::make)
