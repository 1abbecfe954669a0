// `weathergs photo-scene`: one photograph -> a clear dataset with synthetic depth (capture/photo_scene.h).
#include <cstdio>
#include <memory>

#include "apps/command.h"
#include "capture/photo_scene.h"

namespace weathergs::cli {
namespace {

struct PhotoSceneArgs {
  capture::PhotoSceneOptions options;
  std::string out;
};

int run(PhotoSceneArgs& a) {
  const capture::PhotoSceneSummary s = capture::make_photo_scene(a.options, a.out);
  std::printf("wrote %s: %d views of %dx%d panning %.1f deg across the photograph resized to %dx%d\n", a.out.c_str(),
              s.views, a.options.width, a.options.height, s.pan_deg, s.resized_width, s.resized_height);
  return kExitOk;
}

Command make(CLI::App& root) {
  auto a = std::make_shared<PhotoSceneArgs>();
  CLI::App* sub = root.add_subcommand(
      "photo-scene",
      "One photograph -> a clear dataset the weather generator accepts: views panning across it, the "
      "shipped scenes' camera, a synthetic ground-plane depth (docs/scenes.md).");
  auto& o = a->options;
  sub->add_option("--photo", o.photo, "Photograph (png, jpg, tif)")->required();
  sub->add_option("--out", a->out, "Output dataset directory")->required();
  sub->add_option("--views", o.views, "Number of views")->capture_default_str();
  sub->add_option("--width", o.width, "View width in pixels")->capture_default_str();
  sub->add_option("--height", o.height, "View height in pixels")->capture_default_str();
  sub->add_option("--zoom", o.zoom, "The photograph's height after resizing, in view heights (>= 1)")->capture_default_str();
  sub->add_option("--camera-height", o.camera_height_m, "Synthetic depth: camera height over the ground plane (m)")
      ->capture_default_str();
  sub->add_option("--backdrop", o.backdrop_m, "Synthetic depth: distance of everything above the horizon (m)")
      ->capture_default_str();
  sub->add_option("--name", o.name, "Dataset and scene name (default: the output folder's name)");
  return {sub, [a] { return run(*a); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(photo_scene, weathergs::cli::make)
