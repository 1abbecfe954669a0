// Test-time adaptation of the LED (adaptation/led_adaptation.h, `weathergs detect --adapt`).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/dataset.h"
#include "core/error.h"
#include "core/rng.h"
#include "core/json_reader.h"
#include "core/parallel.h"
#include "restoration/led/detect_dataset.h"
#include "restoration/led/led_training.h"
#include "adaptation/led_adaptation.h"
#include "tests/core/test_util.h"
#include "tests/restoration/restoration_test_util.h"

namespace weathergs::adaptation {
namespace {

namespace fs = std::filesystem;
using restoration::led::LensDetector;

using restoration::testing_util::tiny_arch;

struct Scene {
  Dataset ds;
  std::vector<std::string> views;
  std::vector<Image> images;
};

// Six textured views with two drops fixed to the lens; the training views and their images.
Scene drop_scene(const std::string& dir) {
  restoration::testing_util::make_drop_dataset(dir, 6, [](int w, int h, int i) {
    return restoration::testing_util::textured_view_with_drops(w, h, Rng(5, 7, uint64_t(i)), {{0.3 * w, 0.4 * h}, {0.7 * w, 0.6 * h}},
                                                               0.12 * w);
  });
  Scene s;
  s.ds = read_dataset(dir);
  for (const std::string& v : s.ds.split("train")) {
    s.views.push_back(v);
    s.images.push_back(read_image(s.ds.path(ImageKind::kImages, v)));
  }
  return s;
}

LedAdaptOptions small_options() {
  LedAdaptOptions o;
  o.layouts = 2;
  o.iterations = 6;
  o.batch = 2;
  o.threads = 1;
  o.progress = false;
  return o;
}

bool same_attention(const LensDetector& a, const LensDetector& b, const Image& view) {
  return a.attention(view, "view").data == b.attention(view, "view").data;
}

TEST(LedAdaptationTest, LayoutSpecsFollowTheTrainingRecipe) {
  for (int k = 0; k < 8; ++k) {
    const Json s = adapt_layout_spec(k);
    EXPECT_EQ(s["seed"].get<uint64_t>(), kAdaptSeedBase + uint64_t(k) + 1);
    EXPECT_EQ(s["style"].get<std::string>(), kAdaptLayouts[k % 4].style);
    const Json& l = s["effects"]["lens_droplets"];
    EXPECT_EQ(l["count"].get<int>(), kAdaptLayouts[k % 4].count);
    EXPECT_DOUBLE_EQ(l["radius_mm"][0].get<double>(), 0.3);
    EXPECT_DOUBLE_EQ(l["radius_mm"][1].get<double>(), 1.5);
    EXPECT_DOUBLE_EQ(l["glass_distance_m"].get<double>(), 0.015);
  }
}

TEST(LedAdaptationTest, FineTunesACopyDeterministicallyAndReportsIt) {
  testing::TempDir tmp;
  const Scene s = drop_scene(tmp / "scene");
  ASSERT_GE(s.views.size(), 4u);
  const LensDetector base(tiny_arch(), 3);
  const std::vector<float> before = base.attention(s.images[0], "view").data;
  Json report, report2;
  const LensDetector a = adapt_led(base, s.ds, s.views, s.images, small_options(), report);
  const LensDetector b = adapt_led(base, s.ds, s.views, s.images, small_options(), report2);
  // The base network is left as it was; the copy changed; the same inputs give the same network.
  EXPECT_EQ(base.attention(s.images[0], "view").data, before);
  EXPECT_FALSE(same_attention(a, base, s.images[0]));
  EXPECT_TRUE(same_attention(a, b, s.images[0]));
  // Two threads give the same network too (per-example gradients summed in batch order).
  const int threads_before = num_threads();
  set_num_threads(2);
  LedAdaptOptions two = small_options();
  two.threads = 2;
  Json report3;
  const LensDetector c = adapt_led(base, s.ds, s.views, s.images, two, report3);
  set_num_threads(threads_before);
  EXPECT_TRUE(same_attention(a, c, s.images[0]));
  EXPECT_EQ(report3["threads"].get<int>(), 2);
  EXPECT_EQ(report["gradient"].get<std::string>(), "per-example");
  EXPECT_EQ(a.peak_rule().has_value(), base.peak_rule().has_value());
  EXPECT_DOUBLE_EQ(a.threshold(), base.threshold());
  // The report: both layouts, new drops on the views, what was left out, the fine-tune.
  ASSERT_EQ(report["layouts"].size(), 2u);
  double drops = 0;
  for (const Json& l : report["layouts"]) {
    const double f = l["drop_fraction"].get<double>();
    EXPECT_GE(f, 0.0);
    EXPECT_LE(f, 1.0);
    drops += f;
  }
  EXPECT_GT(drops, 0.0) << "no new drop changed any view";
  const double ignored = report["ignored_fraction"].get<double>();
  EXPECT_GE(ignored, 0.0);
  EXPECT_LE(ignored, 1.0);
  EXPECT_EQ(report["iterations"].get<int>(), 6);
  EXPECT_EQ(report["views"].size(), s.views.size());
  EXPECT_TRUE(report["passes"].is_null());  // the count was fixed
  EXPECT_TRUE(std::isfinite(report["loss_last_50"].get<double>()));
  for (float v : a.attention(s.images[1], "view").data) ASSERT_TRUE(std::isfinite(v));
  // By passes: 1.5 passes over 2 layouts x the views in batches of 2.
  LedAdaptOptions by_passes = small_options();
  by_passes.iterations.reset();
  by_passes.passes = 1.5;
  Json report4;
  adapt_led(base, s.ds, s.views, s.images, by_passes, report4);
  EXPECT_EQ(report4["iterations"].get<int>(), int(std::lround(1.5 * 2 * double(s.views.size()) / 2)));
  EXPECT_DOUBLE_EQ(report4["passes"].get<double>(), 1.5);
}

// The default length is a number of passes over the examples, so a dataset with more training views
// gets more iterations; it was set so the quick profile keeps the 100 it was measured with.
TEST(LedAdaptationTest, TheFineTuneLengthScalesWithTheTrainingViews) {
  const LedAdaptOptions o;
  EXPECT_EQ(o.fine_tune_iterations(14), 100);  // the quick profile: 4 layouts x 14 views, batch 4
  EXPECT_EQ(o.fine_tune_iterations(29), 207);  // the paper profile
  EXPECT_EQ(o.fine_tune_iterations(1), 7);
  LedAdaptOptions fixed;
  fixed.iterations = 100;
  EXPECT_EQ(fixed.fine_tune_iterations(29), 100);
  // The settings a resumed run compares hold the resolved count: passes and a fixed count that agree
  // are the same request.
  EXPECT_EQ(adaptation_settings_json(o, 14), adaptation_settings_json(fixed, 14));
  EXPECT_NE(adaptation_settings_json(o, 29), adaptation_settings_json(fixed, 29));
  EXPECT_EQ(adaptation_settings_json(o, 29)["iterations"].get<int>(), 207);
  LedAdaptOptions tiny;
  tiny.passes = 1e-6;
  EXPECT_EQ(tiny.fine_tune_iterations(1), 1);  // at least one
  LedAdaptOptions huge;
  huge.passes = 1000;
  EXPECT_THROW(huge.fine_tune_iterations(1000), InputError);  // 10^6 iterations: over the limit, named
  for (double bad : {0.0, -1.0, 1001.0, std::nan("")}) {
    LedAdaptOptions b;
    b.passes = bad;
    EXPECT_THROW(b.validate(), InputError) << bad;
  }
}

TEST(LedAdaptationTest, BadOptionsAndInputsAreInputErrors) {
  testing::TempDir tmp;
  const Scene s = drop_scene(tmp / "scene");
  const LensDetector base(tiny_arch(), 3);
  Json report;
  for (auto bad : {+[](LedAdaptOptions& o) { o.layouts = 0; }, +[](LedAdaptOptions& o) { o.iterations = 0; },
                   +[](LedAdaptOptions& o) { o.passes = 0; },
                   +[](LedAdaptOptions& o) { o.learning_rate = 0; }, +[](LedAdaptOptions& o) { o.ignore_level = 0; },
                   +[](LedAdaptOptions& o) { o.ignore_dilations = -1; }, +[](LedAdaptOptions& o) { o.batch = 0; }}) {
    LedAdaptOptions o = small_options();
    bad(o);
    EXPECT_THROW(adapt_led(base, s.ds, s.views, s.images, o, report), InputError);
  }
  // No views, names without images, an image of the wrong size, a view the dataset does not have.
  EXPECT_THROW(adapt_led(base, s.ds, {}, {}, small_options(), report), InputError);
  EXPECT_THROW(adapt_led(base, s.ds, s.views, {s.images[0]}, small_options(), report), InputError);
  std::vector<Image> wrong = s.images;
  wrong[1] = Image(8, 8, 3);
  EXPECT_THROW(adapt_led(base, s.ds, s.views, wrong, small_options(), report), InputError);
  std::vector<std::string> unknown = s.views;
  unknown[0] = "no_such_view";
  EXPECT_THROW(adapt_led(base, s.ds, unknown, s.images, small_options(), report), InputError);
}

TEST(LedAdaptationTest, DetectAdaptsThroughItsHookAndRefusesPerViewAveraging) {
  testing::TempDir tmp;
  const Scene s = drop_scene(tmp / "scene");
  LensDetector(tiny_arch(), 3).save(tmp / "w", Json::object());
  restoration::led::DetectDatasetOptions d;
  d.weights = tmp / "w";
  int calls = 0;
  d.adapt = [&](const LensDetector& base, const Dataset& ds, const std::vector<std::string>& views,
                const std::vector<Image>& images, Json& report) {
    ++calls;
    EXPECT_EQ(views, s.views);  // the training views only, in dataset order
    return adapt_led(base, ds, views, images, small_options(), report);
  };
  restoration::led::detect_dataset(tmp / "scene", tmp / "masks", d);
  EXPECT_EQ(calls, 1);
  const Json j = read_json_file((fs::path(tmp / "masks") / restoration::led::kDetectReportFile).string());
  EXPECT_EQ(j["adaptation"]["layouts"].size(), 2u);
  for (const Camera& c : s.ds.cameras) EXPECT_TRUE(fs::exists(fs::path(tmp / "masks") / (c.name + ".png")));
  d.averaging = restoration::led::LedAveraging::kPerView;
  EXPECT_THROW(restoration::led::detect_dataset(tmp / "scene", tmp / "masks2", d), InputError);
  EXPECT_FALSE(fs::exists(tmp / "masks2"));
}

// Weights with a rule calibrated on adapted maps (calibrate-led --maps ... --adapted): detect --adapt
// cuts the adapted network's map with it, detect without --adapt with the weights' own rule; and
// calibrate-led --adapted reads the maps detect --adapt --save-attention wrote.
TEST(LedAdaptationTest, DetectAdaptUsesTheAdaptedRuleCalibratedOnAdaptedMaps) {
  testing::TempDir tmp;
  const Scene s = drop_scene(tmp / "scene");
  LensDetector w(tiny_arch(), 3);
  w.set_peak_rule(restoration::led::LedPeakRule{0.3, 0.3, 0.7});
  w.save(tmp / "w", Json::object());
  restoration::led::DetectDatasetOptions d;
  d.weights = tmp / "w";
  d.save_attention = true;
  d.adapt = [&](const LensDetector& base, const Dataset& ds, const std::vector<std::string>& views,
                const std::vector<Image>& images, Json& report) {
    return adapt_led(base, ds, views, images, small_options(), report);
  };
  restoration::led::detect_dataset(tmp / "scene", tmp / "adapted", d);
  Json j = read_json_file(tmp / "adapted/detect.json");
  EXPECT_EQ(j["adaptation"]["peak_rule"], "peak_rule");  // no adapted rule yet: the weights' own
  EXPECT_DOUBLE_EQ(j["peak_rule"]["fraction"].get<double>(), 0.7);

  restoration::led::RecalibrateLedOptions c;
  c.maps = {tmp / "adapted"};
  c.adapted = true;
  c.search_peak = true;
  c.command = "test";
  const restoration::led::LedCalibration cal = restoration::led::recalibrate_led(tmp / "w", tmp / "w2", c);
  ASSERT_TRUE(cal.peak);
  const LensDetector w2 = LensDetector::load(tmp / "w2");
  ASSERT_TRUE(w2.adapted_peak_rule());
  EXPECT_DOUBLE_EQ(w2.adapted_peak_rule()->fraction, cal.peak->fraction);
  ASSERT_TRUE(w2.peak_rule());  // the plain rule is kept
  EXPECT_DOUBLE_EQ(w2.peak_rule()->fraction, 0.7);
  const Json w2j = read_json_file(tmp / "w2.json");
  EXPECT_EQ(w2j["adapted_calibration"]["held_out"], Json::array({"scene"}));
  EXPECT_EQ(w2j["adapted_calibration"]["adaptations"][0]["iterations"].get<int>(), 6);
  EXPECT_FALSE(w2j.contains("calibration"));  // --adapted writes only its own record
  // Non-adapted maps are refused for the adapted rule.
  restoration::led::DetectDatasetOptions plain = d;
  plain.adapt = nullptr;
  restoration::led::detect_dataset(tmp / "scene", tmp / "plain", plain);
  c.maps = {tmp / "plain"};
  EXPECT_THROW(restoration::led::recalibrate_led(tmp / "w", tmp / "w3", c), InputError);
  EXPECT_FALSE(fs::exists(tmp / "w3.json"));

  // An adapted rule that differs from the plain one, to tell which one detect used.
  LensDetector w4 = LensDetector::load(tmp / "w");
  w4.set_adapted_peak_rule(restoration::led::LedPeakRule{0.4, 0.5, 0.85});
  w4.save(tmp / "w4", Json::object());
  d.weights = plain.weights = tmp / "w4";
  restoration::led::detect_dataset(tmp / "scene", tmp / "adapted4", d);
  j = read_json_file(tmp / "adapted4/detect.json");
  EXPECT_EQ(j["adaptation"]["peak_rule"], "adapted_peak_rule");
  EXPECT_DOUBLE_EQ(j["peak_rule"]["fraction"].get<double>(), 0.85);
  EXPECT_DOUBLE_EQ(j["peak_rule"]["low"].get<double>(), 0.4);
  restoration::led::detect_dataset(tmp / "scene", tmp / "plain4", plain);
  EXPECT_DOUBLE_EQ(read_json_file(tmp / "plain4/detect.json")["peak_rule"]["fraction"].get<double>(), 0.7);
  // An explicit --peak still overrides both.
  d.mask.peak = restoration::led::LedPeakRule{0.2, 0.2, 0.5};
  restoration::led::detect_dataset(tmp / "scene", tmp / "override", d);
  EXPECT_DOUBLE_EQ(read_json_file(tmp / "override/detect.json")["peak_rule"]["fraction"].get<double>(), 0.5);
}

}  // namespace
}  // namespace weathergs::adaptation
