// Lens droplets through the weather pipeline: `weathergs weather` alone and with fog and rain, the
// ground truth it writes, and determinism across thread counts and view order.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/image.h"
#include "core/parallel.h"
#include "generator/weather.h"
#include "tests/core/test_util.h"
#include "tests/generator/test_scene.h"

namespace weathergs::generator {
namespace {

namespace fs = std::filesystem;
using testing::SceneOptions;
using testing::TempDir;

const Json kLensSpec = {{"seed", 5},
                        {"effects",
                         {{"lens_droplets",
                           {{"count", 25}, {"radius_mm", {1.5, 4.0}}, {"contact_angle_deg", {40, 110}}, {"mask_rule", "coverage"}}}}}};

void run_cli(const std::string& in, const Json& spec, const std::string& out, int threads) {
  const std::string spec_path = out + ".spec.json";
  write_file_atomic(spec_path, spec.dump());
  const std::string cmd = std::string(WEATHERGS_BINARY) + " --quiet --threads " + std::to_string(threads) +
                          " weather --in " + in + " --spec " + spec_path + " --out " + out;
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
}

std::vector<std::string> view_names(const Dataset& d) {
  std::vector<std::string> v;
  for (const Camera& c : d.cameras) v.push_back(c.name);
  return v;
}

TEST(WeatherLens, AloneThroughTheCommandWritesGroundTruth) {
  TempDir tmp;
  SceneOptions scene;
  scene.views = 3;
  testing::make_clean_dataset(tmp / "clean", scene);
  run_cli(tmp / "clean", kLensSpec, tmp / "out", 2);
  const Dataset out = read_dataset(tmp / "out");
  EXPECT_EQ(out.info.weather, "lens_droplets");
  const Json& gen = *out.info.generator;
  ASSERT_EQ(gen["stages"].size(), 1u);
  EXPECT_EQ(gen["stages"][0]["name"], "lens_droplets");
  // The resolved spec records every default.
  EXPECT_EQ(gen["spec"]["effects"]["lens_droplets"]["samples_per_pixel"], 4);
  EXPECT_EQ(gen["spec"]["effects"]["lens_droplets"]["attach"], "lens");
  const Json& views = gen["lens_droplets"]["views"];
  ASSERT_EQ(views.size(), 3u);
  int covered_total = 0;
  for (size_t i = 0; i < out.cameras.size(); ++i) {
    const std::string v = out.cameras[i].name;
    EXPECT_EQ(views[i]["view"], v);
    // Lens-attached: the same drops in every view.
    EXPECT_EQ(views[i]["drops"].dump(), views[0]["drops"].dump());
    const Image mask = read_mask(out.path(ImageKind::kLensMask, v));
    const Image coverage = read_image(out.layer_path(layout::kLensCoverageLayer, v, ".exr"));
    const Image img = read_image(out.path(ImageKind::kImages, v)), clean = read_image(out.path(ImageKind::kClean, v));
    ASSERT_EQ(mask.width, out.cameras[i].width);
    ASSERT_EQ(coverage.channels, 1);
    int covered = 0, unchanged_outside = 0, outside = 0;
    for (int y = 0; y < mask.height; ++y)
      for (int x = 0; x < mask.width; ++x) {
        const float c = coverage.at(x, y);
        ASSERT_TRUE(c >= 0 && c <= 1);
        EXPECT_EQ(mask.at(x, y), c >= 0.1f ? 1.f : 0.f);
        covered += mask.at(x, y) > 0;
        if (c == 0) {
          ++outside;
          // Untouched pixels go through linear and back: equal up to one 8-bit step.
          bool same = true;
          for (int ch = 0; ch < 3; ++ch) same &= std::abs(img.at(x, y, ch) - clean.at(x, y, ch)) <= 1.5f / 255;
          unchanged_outside += same;
        }
      }
    EXPECT_EQ(unchanged_outside, outside);
    covered_total += covered;
  }
  EXPECT_GT(covered_total, 100);
}

TEST(WeatherLens, AfterFogAndRainDeterministicAcrossThreadsAndViewOrder) {
  TempDir tmp;
  SceneOptions scene;
  scene.views = 4;
  testing::make_clean_dataset(tmp / "clean", scene);
  Json spec = kLensSpec;
  spec["effects"]["rain"] = {{"rate_mm_h", 20}};
  spec["effects"]["fog"] = {{"visibility_m", 300}};
  run_cli(tmp / "clean", spec, tmp / "t1", 1);
  run_cli(tmp / "clean", spec, tmp / "t2", 2);
  WeatherRunOptions reversed;
  const Dataset clean = read_dataset(tmp / "clean");
  reversed.view_order = view_names(clean);
  std::reverse(reversed.view_order.begin(), reversed.view_order.end());
  run_weather(tmp / "clean", JsonReader(spec, "spec.json"), tmp / "rev", reversed);

  const Dataset d1 = read_dataset(tmp / "t1");
  EXPECT_EQ(d1.info.weather, "rain+fog+lens_droplets");
  std::vector<std::string> stage_names;
  for (const Json& s : d1.info.generator->at("stages")) stage_names.push_back(s["name"]);
  EXPECT_EQ(stage_names, (std::vector<std::string>{"fog", "rain", "lens_droplets"}));
  for (const std::string& other : {std::string("t2"), std::string("rev")}) {
    for (const std::string& v : view_names(d1)) {
      for (const std::string& f : {"images/" + v + ".png", "masks/lens/" + v + ".png",
                                   "masks/particles/" + v + ".png", "layers/lens_coverage/" + v + ".exr"}) {
        EXPECT_EQ(read_file(tmp / ("t1/" + f)), read_file(tmp / (other + "/" + f))) << other << " " << f;
      }
    }
    EXPECT_EQ(d1.info.generator->at("lens_droplets").dump(),
              read_dataset(tmp / other).info.generator->at("lens_droplets").dump());
  }
}

TEST(WeatherLens, WindowAttachRecordsTheResolvedPaneAndBadSpecsFail) {
  TempDir tmp;
  SceneOptions scene;
  scene.views = 2;
  testing::make_clean_dataset(tmp / "clean", scene);
  Json spec = kLensSpec;
  spec["effects"]["lens_droplets"]["attach"] = "window";
  spec["effects"]["lens_droplets"]["glass_distance_m"] = 0.2;
  const Json block = run_weather(tmp / "clean", JsonReader(spec, "spec.json"), tmp / "out", {});
  const Json& window = block["spec"]["effects"]["lens_droplets"]["window"];
  ASSERT_TRUE(window.is_object());
  // The first camera sits at (0, 0, 1.6) looking along world +y.
  EXPECT_NEAR(window["center_world"][1].get<double>(), 0.2, 1e-9);
  EXPECT_NEAR(window["normal_world"][1].get<double>(), 1.0, 1e-9);
  // The cameras move 0.4 m sideways and the pane stays: the second view sees fewer of its drops.
  const Json& views = block["lens_droplets"]["views"];
  EXPECT_NE(views[0]["drops"].dump(), views[1]["drops"].dump());

  Json bad = kLensSpec;
  bad["effects"]["lens_droplets"]["contact_angle_deg"] = 190;
  try {
    run_weather(tmp / "clean", JsonReader(bad, "spec.json"), tmp / "bad", {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("spec.json:/effects/lens_droplets/contact_angle_deg"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(tmp / "bad"));
}

}  // namespace
}  // namespace weathergs::generator
