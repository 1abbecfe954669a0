// `weathergs triangulate`: COLMAP known-pose triangulation of an existing dataset -> sparse/0 (or
// sparse_clean/0), the SfM points 3DGS initializes from (docs/scenes.md).
#include <cstdio>
#include <memory>

#include "apps/command.h"
#include "capture/colmap.h"

namespace weathergs::cli {
namespace {

struct TriangulateArgs {
  std::string data, images = "images", views = "all";
  capture::TriangulateOptions options;
};

int run(TriangulateArgs& a) {
  a.options.images = a.images == "clean" ? capture::TriangulateImages::kClean : capture::TriangulateImages::kImages;
  a.options.views = a.views == "train" ? capture::TriangulateViews::kTrain : capture::TriangulateViews::kAll;
  std::string model;
  const capture::TriangulationResult r = capture::triangulate_dataset(a.data, a.options, &model);
  std::printf("wrote %s: %d points from %d of %d images, mean track length %.2f, mean reprojection error %.3f px "
              "(%.1f s)\n",
              model.c_str(), r.stats.points, r.stats.registered_images, r.stats.images, r.stats.mean_track_length,
              r.stats.mean_reprojection_error_px, r.seconds);
  return kExitOk;
}

Command make(CLI::App& root) {
  auto a = std::make_shared<TriangulateArgs>();
  CLI::App* sub = root.add_subcommand(
      "triangulate",
      "SfM points for a dataset with known poses (COLMAP features + point_triangulator, as generate does): "
      "writes sparse/0 from images/ or sparse_clean/0 from clean/.");
  sub->add_option("--data", a->data, "Dataset folder")->required();
  sub->add_option("--images", a->images, "Which images: images (-> sparse/0) or clean (-> sparse_clean/0)")
      ->capture_default_str()->check(CLI::IsMember({"images", "clean"}));
  sub->add_option("--views", a->views, "Views to match: all (as generate) or train (the train split only)")
      ->capture_default_str()->check(CLI::IsMember({"all", "train"}));
  sub->add_flag("--force", a->options.force, "Replace an existing model");
  sub->add_option("--colmap", a->options.colmap.executable, "COLMAP executable")->capture_default_str();
  sub->add_option("--colmap-threads", a->options.colmap.num_threads, "COLMAP threads (-1 = all cores)")
      ->capture_default_str();
  return {sub, [a] { return run(*a); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(triangulate, weathergs::cli::make)
