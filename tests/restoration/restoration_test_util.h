// Helpers shared by the restoration tests: the `weathergs` binary as a user runs it, and a generated
// dataset whose views carry lens drops.
#pragma once

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "core/dataset.h"
#include "core/rng.h"
#include "restoration/led/lens_detector.h"
#include "tests/generator/test_scene.h"

namespace weathergs::restoration::testing_util {

// A textured view (uniform noise in [0.2, 0.5] drawn from `rng`) with a blurry bright disc of radius r
// px at each centre (drops on the lens), and their mask.
inline led::LedExample textured_view_with_drops(int w, int h, Rng rng, const std::vector<std::array<double, 2>>& centres, double r) {
  led::LedExample e{Image(w, h, 3), Image(w, h, 1, ColorSpace::kLinear)};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) e.image.at(x, y, c) = 0.2f + 0.3f * rng.uniform();
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (const auto& [cx, cy] : centres) {
        const double d = std::hypot(x + 0.5 - cx, y + 0.5 - cy);
        if (d < r) {
          e.mask.at(x, y) = 1;
          for (int c = 0; c < 3; ++c) e.image.at(x, y, c) = float(0.85 - 0.2 * d / r);
        }
      }
  return e;
}

// A network small enough for a test to train in seconds.
inline led::LedArchitecture tiny_arch() {
  led::LedArchitecture a;
  a.width = 32;
  a.channels = 6;
  a.steps = 2;
  a.residual_blocks = 2;
  return a;
}

// Runs `weathergs --quiet ARGS`, output to `log`; the exit status (-1 if it did not exit).
inline int run_cli(const std::string& args, const std::string& log) {
  const int st = std::system((std::string(WEATHERGS_BINARY) + " --quiet " + args + " > '" + log + "' 2>&1").c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

// A clean test dataset of `views` views whose images/ carry the drops of view(width, height, index)
// (its image inside its mask, the clean view elsewhere) and masks/lens/ their masks.
inline void make_drop_dataset(const std::string& dir, int views, const std::function<led::LedExample(int, int, int)>& view) {
  namespace fs = std::filesystem;
  testing::SceneOptions so;
  so.views = views;
  testing::make_clean_dataset(dir, so);
  fs::create_directories(fs::path(dir) / "images");
  fs::create_directories(fs::path(dir) / "masks/lens");
  const Dataset ds = read_dataset(dir);
  for (size_t i = 0; i < ds.cameras.size(); ++i) {
    const Camera& c = ds.cameras[i];
    const led::LedExample e = view(c.width, c.height, int(i));
    Image img = read_image(ds.path(ImageKind::kClean, c.name));
    for (int y = 0; y < c.height; ++y)
      for (int x = 0; x < c.width; ++x)
        if (e.mask.at(x, y) > 0)
          for (int k = 0; k < 3; ++k) img.at(x, y, k) = e.image.at(x, y, k);
    write_image(ds.path(ImageKind::kImages, c.name), img);
    write_mask(ds.path(ImageKind::kLensMask, c.name), e.mask);
  }
}

}  // namespace weathergs::restoration::testing_util
