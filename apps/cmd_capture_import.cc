// `weathergs import`: real footage -> dataset (keyframes, COLMAP mapper, cameras.json, sparse/0).
#include <cstdio>
#include <memory>

#include "apps/command.h"
#include "capture/import.h"

namespace weathergs::cli {
namespace {

struct ImportArgs {
  capture::ImportOptions options;
  std::string out;
};

int run(ImportArgs& a) {
  const capture::ImportSummary s = capture::import_footage(a.options, a.out);
  std::printf("imported %s: %d keyframes, %d registered, %d points, mean reprojection error %.3f px "
              "(extract %.1f s, colmap %.1f s)\n",
              a.out.c_str(), s.frames, s.registered, s.stats.points, s.stats.mean_reprojection_error_px, s.extract_s,
              s.colmap_s);
  return kExitOk;
}

Command make(CLI::App& root) {
  auto a = std::make_shared<ImportArgs>();
  CLI::App* sub = root.add_subcommand(
      "import",
      "Import real footage (a video or a folder of images): keyframes, COLMAP mapper with unknown poses, "
      "a dataset without clean ground truth (docs/scenes.md).");
  sub->add_option("--video", a->options.video, "Video file (mp4, avi, ... as OpenCV decodes it)");
  sub->add_option("--images", a->options.images_dir, "Folder of images (png, jpg), in name order");
  sub->add_option("--every", a->options.every, "Keep every N-th video frame")->capture_default_str();
  sub->add_option("--max-frames", a->options.max_frames, "At most this many keyframes")->capture_default_str();
  sub->add_option("--max-size", a->options.max_size_px, "Downscale to this long side in pixels (0 = keep)")
      ->capture_default_str();
  sub->add_option("--name", a->options.name, "Dataset name (default: the output folder's name)");
  sub->add_option("--weather", a->options.weather, "What the footage shows: clear, rain, snow, ...")
      ->capture_default_str();
  sub->add_option("--colmap", a->options.colmap.executable, "COLMAP executable")->capture_default_str();
  sub->add_option("--out", a->out, "Output dataset directory")->required();
  return {sub, [a] { return run(*a); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(import, weathergs::cli::make)
