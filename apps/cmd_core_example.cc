// weathergs example: writes a tiny synthetic benchmark (ground-truth datasets plus renders of three
// toy degradations) so the evaluator, leaderboard and check can be tried in seconds. It is what
// `make demo` scores; real datasets come from `weathergs generate`.
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "apps/command.h"
#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/dataset_identity.h"
#include "core/rng.h"

namespace weathergs::cli {
namespace {

namespace fs = std::filesystem;

struct ExampleArgs {
  std::string out;
  int width = 120, height = 80, views = 9;
  uint64_t seed = 7;
};

// A smooth, non-repeating test pattern that shifts with the view index (a camera panning sideways).
Image clean_view(int scene, int view, int w, int h) {
  Image img(w, h, 3, ColorSpace::kSRGB);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double u = (x + 2.0 * view) / w, v = double(y) / h;
      const double base = 0.5 + 0.25 * std::sin(7.0 * u + 3.0 * scene) * std::cos(5.0 * v + scene);
      const double ring = 0.5 + 0.5 * std::sin(40.0 * std::hypot(u - 0.6, v - 0.4 - 0.1 * scene));
      img.at(x, y, 0) = float(0.2 + 0.6 * base);
      img.at(x, y, 1) = float(0.15 + 0.5 * ring * base);
      img.at(x, y, 2) = float(0.3 + 0.4 * (1.0 - base) + 0.1 * scene);
    }
  return img;
}

Image degrade(const Image& clean, const std::string& method, Rng& rng) {
  Image out = clean;
  const int w = clean.width, h = clean.height;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        float v;
        if (method == "box-blur") {  // 3x3 box blur: a method that loses detail
          double s = 0;
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx)
              s += clean.at(std::clamp(x + dx, 0, w - 1), std::clamp(y + dy, 0, h - 1), c);
          v = float(s / 9);
        } else if (method == "noise") {  // sensor-like noise, sigma 0.02
          v = clean.at(x, y, c) + float(0.02 * rng.normal());
        } else {  // "shift": a 1-pixel pose error
          v = clean.at(std::min(x + 1, w - 1), y, c);
        }
        out.at(x, y, c) = std::clamp(v, 0.f, 1.f);
      }
  return out;
}

int run_example(const ExampleArgs& a) {
  if (a.width < 32 || a.height < 32 || a.views < 2)
    throw InputError("example", "width and height must be >= 32 and views >= 2, got width " + std::to_string(a.width) +
                                    ", height " + std::to_string(a.height) + ", views " + std::to_string(a.views));
  AtomicDirectory out(a.out);
  const std::vector<std::string> scenes = {"park", "yard"}, weathers = {"rain", "snow"};
  const std::vector<std::string> methods = {"box-blur", "noise", "shift"};
  for (size_t s = 0; s < scenes.size(); ++s)
    for (const std::string& weather : weathers) {
      const std::string name = scenes[s] + "_" + weather;
      Dataset ds;
      ds.root = (fs::path(out.path()) / "datasets" / name).string();
      for (const char* sub : {"clean", "images"}) fs::create_directories(fs::path(ds.root) / sub);
      std::vector<std::string> names;
      for (int v = 0; v < a.views; ++v) {
        char n[16];
        std::snprintf(n, sizeof n, "%03d", v);
        names.push_back(n);
        Camera cam;
        cam.name = n;
        cam.width = a.width;
        cam.height = a.height;
        cam.fx = cam.fy = 0.9 * a.width;
        cam.cx = a.width / 2.0;
        cam.cy = a.height / 2.0;
        cam.camera_from_world(0, 3) = -0.05 * v;  // panning sideways
        cam.time_s = v * 0.5;
        cam.exposure_s = 1.0 / 60;
        ds.cameras.push_back(cam);
        Image clean = clean_view(int(s), v, a.width, a.height);
        write_image(ds.path(ImageKind::kClean, n), clean);
        // Toy weather for images/: bright vertical streaks (the real generator is `weathergs weather`).
        Rng rng(a.seed, 1, uint64_t(s * 1000 + v) * 2 + (weather == "snow"));
        for (int k = 0; k < 25; ++k) {
          int x = int(rng.uniform_int(uint32_t(a.width))), y0 = int(rng.uniform_int(uint32_t(a.height)));
          int len = weather == "rain" ? 8 : 2;
          for (int y = y0; y < std::min(a.height, y0 + len); ++y)
            for (int c = 0; c < 3; ++c) clean.at(x, y, c) = 0.5f * clean.at(x, y, c) + 0.5f;
        }
        write_image(ds.path(ImageKind::kImages, n), clean);
      }
      ds.info.name = name;
      ds.info.scene = scenes[s];
      ds.info.weather = weather;
      ds.info.splits = llff_splits(names);
      ds.info.splits_rule = kLlffSplitRule;
      write_dataset(ds);
      // Recorded as `generate` records it, so that a changed file is refused when scored.
      ds.info.identity = compute_dataset_identity(ds.root).to_json(true);
      write_dataset_json(ds.file(layout::kDatasetJson), ds.info);
      for (size_t m = 0; m < methods.size(); ++m) {
        const fs::path dir = fs::path(out.path()) / "renders" / methods[m] / name;
        fs::create_directories(dir);
        for (const std::string& v : ds.info.splits.at("test")) {
          Rng rng(a.seed, 2, uint64_t(s * 100000 + m * 1000) + uint64_t(std::stoi(v)));
          write_image((dir / (v + ".png")).string(), degrade(read_image(ds.path(ImageKind::kClean, v)), methods[m], rng));
        }
        write_file_atomic((dir / "info.json").string(),
                          Json{{"method", methods[m]}, {"train_seconds", 0}, {"iterations", 0}}.dump(2) + "\n");
      }
    }
  out.commit();
  std::printf("wrote %s: datasets/<scene>_<weather> (2 scenes x rain, snow) and renders/<method>/<dataset> "
              "for methods box-blur, noise, shift\n", out.final_path().c_str());
  return kExitOk;
}

Command make_example(CLI::App& root) {
  auto args = std::make_shared<ExampleArgs>();
  CLI::App* sub = root.add_subcommand("example", "Write a tiny synthetic benchmark with toy method renders (for trying the evaluator)");
  sub->add_option("-o,--out", args->out, "Output folder (replaced atomically)")->required();
  sub->add_option("--width", args->width, "Image width")->capture_default_str();
  sub->add_option("--height", args->height, "Image height")->capture_default_str();
  sub->add_option("--views", args->views, "Views per dataset (every 8th is a test view)")->capture_default_str();
  sub->add_option("--seed", args->seed, "Seed")->capture_default_str();
  return {sub, [args] { return run_example(*args); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(example, weathergs::cli::make_example)
