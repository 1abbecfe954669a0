// `weathergs filter`: the Atmospheric Effect Filter over a dataset, classical or learned, with the
// weather selector (docs/restoration.md).
#include <cstdio>
#include <map>
#include <memory>

#include "apps/command.h"
#include "apps/resources.h"
#include "restoration/aef/filter_dataset.h"

namespace weathergs::cli {
namespace {

namespace r = weathergs::restoration::aef;

struct FilterArgs {
  std::string data, out, images = "images", mode = "restore", method = "learned", task = "auto", select = "per-scene";
  std::string weights;
  r::FilterDatasetOptions options;
};

int run(FilterArgs& a) {
  auto& o = a.options;
  o.input = a.images == "clean" ? ImageKind::kClean : ImageKind::kImages;
  o.mode = a.mode == "mask" ? r::FilterMode::kMask : r::FilterMode::kRestore;
  o.method = a.method == "tophat" ? r::FilterMethod::kTopHat : r::FilterMethod::kLearned;
  const std::map<std::string, r::AefTask> tasks{{"always", r::AefTask::kAlways}, {"auto", r::AefTask::kAuto},
                                               {"derain", r::AefTask::kDerain}, {"desnow", r::AefTask::kDesnow},
                                               {"none", r::AefTask::kNone}};
  o.task = tasks.at(a.task);
  o.scope = a.select == "per-view" ? r::SelectScope::kPerView : r::SelectScope::kPerScene;
  const bool needs_weights = (o.method == r::FilterMethod::kLearned && o.task != r::AefTask::kNone) ||
                             (o.task == r::AefTask::kAuto && o.instruction.empty());
  if (needs_weights) o.aef_weights = find_aef_weights(a.weights);
  const r::FilterDatasetReport rep = r::filter_dataset(a.data, a.out, o);
  double mean = 0;
  std::map<std::string, int> plugins;
  for (const auto& v : rep.views) {
    mean += v.mask_fraction / double(rep.views.size());
    ++plugins[v.plugin == r::WeatherClass::kRain ? "derain" : v.plugin == r::WeatherClass::kSnow ? "desnow" : "none"];
  }
  std::string used;
  for (const auto& [name, n] : plugins) used += (used.empty() ? "" : ", ") + name + " x" + std::to_string(n);
  std::printf("filtered %zu views (%s, %s) in %.2f s (%.1f ms per view): %.1f%% of the pixels masked as particles on average\n",
              rep.views.size(), r::to_string(o.method), used.c_str(), rep.seconds,
              1000 * rep.seconds / double(std::max<size_t>(1, rep.views.size())), 100 * mean);
  if (rep.selected)
    std::printf("selector (%s): scene cosines snow %.3f rain %.3f none %.3f -> %s; %.1f ms per view\n", r::to_string(o.scope),
                rep.scene.cosine[0], rep.scene.cosine[1], rep.scene.cosine[2], r::to_string(rep.scene.choice),
                1000 * rep.selector_seconds_per_view);
  std::printf("wrote %s\n", a.out.c_str());
  return kExitOk;
}

Command make(CLI::App& root) {
  auto a = std::make_shared<FilterArgs>();
  CLI::App* sub = root.add_subcommand(
      "filter",
      "Remove falling particles (snow, rain streaks) from every view of a dataset: the Atmospheric Effect Filter, learned "
      "(derain/desnow plugins chosen by the weather selector) or classical (morphological top-hat); docs/restoration.md.");
  sub->add_option("--data", a->data, "Dataset folder")->required();
  sub->add_option("--out", a->out, "Output folder: <view>.png (+ masks/<view>.png) and filter.json")->required();
  sub->add_option("--images", a->images, "Which images: images or clean")
      ->capture_default_str()->check(CLI::IsMember({"images", "clean"}));
  sub->add_option("--mode", a->mode,
                  "restore: filtered images (+ masks/); mask: only the particle masks (255 = particle)")
      ->capture_default_str()->check(CLI::IsMember({"restore", "mask"}));
  sub->add_option("--method", a->method, "learned: the derain/desnow plugins (models/aef); tophat: the classical filter")
      ->capture_default_str()->check(CLI::IsMember({"learned", "tophat"}));
  sub->add_option("--task", a->task,
                  "auto: the weather selector picks derain, desnow or none; derain/desnow/none: forced on every view; "
                  "always (tophat only): filter every view without selection")
      ->capture_default_str()->check(CLI::IsMember({"auto", "derain", "desnow", "none", "always"}));
  sub->add_option("--instruction", a->options.instruction,
                  "Override the selector with an instruction: \"Remove snowy effect in the scene\", \"Remove rainy effect in "
                  "the scene.\" or \"none\"");
  sub->add_option("--select", a->select, "auto: one plugin per scene (mean embedding) or per view (the paper)")
      ->capture_default_str()->check(CLI::IsMember({"per-scene", "per-view"}));
  sub->add_option("--weights", a->weights, "Folder of the learned weights (derain, desnow, selector); default models/aef");
  sub->add_option("--alpha-threshold", a->options.alpha_threshold, "learned: particle mask where alpha >= this")
      ->capture_default_str();
  sub->add_option("--radius", a->options.filter.radius_px_at_300,
                  "tophat: structuring disk radius in pixels at 300 px image width (scaled with the width)")
      ->capture_default_str();
  sub->add_option("--threshold", a->options.filter.threshold, "tophat: threshold on the sRGB luminance's top-hat")
      ->capture_default_str();
  sub->add_option("--dilate", a->options.filter.dilate_px, "tophat: grow the particle mask by this many pixels")
      ->capture_default_str();
  return {sub, [a] { return run(*a); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(filter, weathergs::cli::make)
