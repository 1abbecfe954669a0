// `weathergs filter`: the classical Atmospheric Effect Filter over a dataset (docs/restoration.md).
#include <cstdio>
#include <memory>

#include "apps/command.h"
#include "restoration/filter_dataset.h"

namespace weathergs::cli {
namespace {

struct FilterArgs {
  std::string data, out, images = "images", mode = "restore";
  restoration::FilterDatasetOptions options;
};

int run(FilterArgs& a) {
  a.options.input = a.images == "clean" ? ImageKind::kClean : ImageKind::kImages;
  a.options.mode = a.mode == "mask" ? restoration::FilterMode::kMask : restoration::FilterMode::kRestore;
  const restoration::FilterDatasetReport r = restoration::filter_dataset(a.data, a.out, a.options);
  double mean = 0;
  for (const auto& v : r.views) mean += v.mask_fraction / double(r.views.size());
  std::printf("filtered %zu views in %.2f s (%.1f ms per view): %.1f%% of the pixels masked as particles on average\n"
              "wrote %s\n",
              r.views.size(), r.seconds, 1000 * r.seconds / std::max<size_t>(1, r.views.size()), 100 * mean, a.out.c_str());
  return kExitOk;
}

Command make(CLI::App& root) {
  auto a = std::make_shared<FilterArgs>();
  CLI::App* sub = root.add_subcommand(
      "filter",
      "Remove falling particles (snow, rain streaks) from every view of a dataset: the classical Atmospheric "
      "Effect Filter (morphological top-hat; docs/restoration.md).");
  sub->add_option("--data", a->data, "Dataset folder")->required();
  sub->add_option("--out", a->out, "Output folder: <view>.png (+ masks/<view>.png) and filter.json")->required();
  sub->add_option("--images", a->images, "Which images: images or clean")
      ->capture_default_str()->check(CLI::IsMember({"images", "clean"}));
  sub->add_option("--mode", a->mode,
                  "restore: filtered images (+ masks/); mask: only the particle masks (255 = particle)")
      ->capture_default_str()->check(CLI::IsMember({"restore", "mask"}));
  sub->add_option("--radius", a->options.filter.radius_px_at_300,
                  "Structuring disk radius in pixels at 300 px image width (scaled with the width)")
      ->capture_default_str();
  sub->add_option("--threshold", a->options.filter.threshold, "Top-hat threshold on the sRGB luminance")
      ->capture_default_str();
  sub->add_option("--dilate", a->options.filter.dilate_px, "Grow the particle mask by this many pixels")
      ->capture_default_str();
  return {sub, [a] { return run(*a); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(filter, weathergs::cli::make)
