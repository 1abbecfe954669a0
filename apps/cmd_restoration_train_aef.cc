// `weathergs train-aef`: trains a learned AEF plugin (derain, desnow) or the weather selector
// (docs/restoration.md, make models).
#include <cstdio>
#include <memory>

#include "apps/command.h"
#include "restoration/aef/aef_training.h"

namespace weathergs::cli {
namespace {

namespace r = weathergs::restoration::aef;

struct TrainAefArgs {
  std::vector<std::string> data, held_out;
  std::string out, model;
  int iterations = 0, batch = 0, threads = 0;
  double learning_rate = 0;
  uint64_t seed = 1;
  r::TrainAefOptions plugin;
  r::TrainSelectorOptions selector;
  std::string command;
};

void print_curve(const std::vector<double>& c) {
  std::printf("loss %.4f -> %.4f\n", c.empty() ? 0.0 : c.front(), c.empty() ? 0.0 : c.back());
}

int run(TrainAefArgs& a) {
  if (a.model == "selector") {
    auto& t = a.selector.train;
    if (a.iterations > 0) t.iterations = a.iterations;
    if (a.batch > 0) t.batch = a.batch;
    if (a.learning_rate > 0) t.learning_rate = a.learning_rate;
    t.seed = a.seed;
    t.threads = a.threads;
    a.selector.command = a.command;
    const r::TrainSelectorResult res = r::train_selector(a.data, a.held_out, a.out, a.selector);
    std::printf("trained the weather selector on %zu views (%lld parameters) in %.1f s; ", res.examples,
                static_cast<long long>(res.record.parameters), res.record.seconds);
    print_curve(res.record.loss_curve);
    if (!a.held_out.empty()) {
      const auto& c = res.calibration;
      std::printf("calibrated theta %.2f: held-out accuracy %.3f per view (%d views), %.3f per scene (%d datasets)\n", c.theta,
                  c.view_accuracy, c.views, c.scene_accuracy, c.scenes);
      for (const auto& d : c.per_dataset)
        std::printf("  %-24s %-5s %d/%d views right, scene -> %s\n", d.at("dataset").get<std::string>().c_str(),
                    d.at("label").get<std::string>().c_str(), d.at("views_right").get<int>(), d.at("views").get<int>(),
                    d.at("scene_choice").get<std::string>().c_str());
    }
  } else {
    auto& t = a.plugin.train;
    if (a.iterations > 0) t.iterations = a.iterations;
    if (a.batch > 0) t.batch = a.batch;
    if (a.learning_rate > 0) t.learning_rate = a.learning_rate;
    t.seed = a.seed;
    t.threads = a.threads;
    a.plugin.command = a.command;
    const r::AefPluginKind kind = a.model == "derain" ? r::AefPluginKind::kDerain : r::AefPluginKind::kDesnow;
    const r::TrainAefResult res = r::train_aef(kind, a.data, a.held_out, a.out, a.plugin);
    std::printf("trained the %s plugin on %zu views (%lld parameters) in %.1f s; ", a.model.c_str(), res.examples,
                static_cast<long long>(res.record.parameters), res.record.seconds);
    print_curve(res.record.loss_curve);
    for (const auto& s : res.held_out)
      std::printf("  held out %-24s PSNR to the no-particle target: input %.2f dB, restored %.2f dB (%+.2f)\n", s.dataset.c_str(),
                  s.psnr_input, s.psnr_restored, s.psnr_restored - s.psnr_input);
  }
  std::printf("wrote %s.json and %s.bin\n", a.out.c_str(), a.out.c_str());
  return kExitOk;
}

Command make(CLI::App& root) {
  auto a = std::make_shared<TrainAefArgs>();
  CLI::App* sub = root.add_subcommand(
      "train-aef",
      "Train a learned AEF plugin (derain, desnow) on generated datasets (images/, targets/no_particles/, masks/particles/) "
      "or the weather selector, calibrated on held-out datasets (docs/restoration.md; `make models` runs the recipe).");
  sub->add_option("--model", a->model, "derain, desnow or selector")->required()->check(CLI::IsMember({"derain", "desnow", "selector"}));
  sub->add_option("--data", a->data, "Training datasets")->required();
  sub->add_option("--held-out", a->held_out, "Held-out datasets (scores; the selector's theta), never trained on");
  sub->add_option("--out", a->out, "Weights stem: writes <stem>.json and <stem>.bin")->required();
  sub->add_option("--iterations", a->iterations, "Training iterations (0 or unset: plugins 5000, selector 1500)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--batch", a->batch, "Examples per iteration (0 or unset: plugins 8 crops, selector 16 views)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--learning-rate", a->learning_rate, "Adam learning rate, cosine-decayed to 5% (default 0.002 / 0.003)");
  sub->add_option("--seed", a->seed, "Seed of the initialization and of the batch order")->capture_default_str();
  sub->add_option("--threads", a->threads, "libtorch threads (0 = all cores; 1 for reproducible weights)")->capture_default_str();
  sub->add_option("--crop", a->plugin.train.crop, "Plugins: square crop size in pixels")->capture_default_str();
  sub->add_option("--channels", a->plugin.train.arch.channels, "Plugins: full-resolution feature channels")->capture_default_str();
  sub->add_option("--alpha-weight", a->plugin.train.alpha_weight, "Plugins: weight of the alpha BCE")->capture_default_str();
  sub->add_option("--ssim-weight", a->plugin.train.ssim_weight, "Plugins: weight of D-SSIM against L1")->capture_default_str();
  sub->add_option("--prior-gain", a->plugin.train.arch.prior_gain, "Plugins: slope of the top-hat alpha prior (0 = none)")
      ->capture_default_str();
  return {sub, [a, sub] {
            a->command = recorded_command("train-aef", *sub);
            return run(*a);
          }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(train_aef, weathergs::cli::make)
