// Calibrating the LED's post-processing (restoration/led/led_training.h): from precomputed maps, under a
// precision bound, and `weathergs calibrate-led --maps` over what `detect --save-attention` wrote.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/error.h"
#include "core/json_reader.h"
#include "restoration/led/led_training.h"
#include "tests/core/test_util.h"
#include "tests/restoration/restoration_test_util.h"

namespace weathergs::restoration::led {
namespace {

namespace fs = std::filesystem;
using testing_util::run_cli;
using testing_util::tiny_arch;

// A 64x48 held-out map: a drop of radius 8 px (the truth, on every one of two views) under a
// Gaussian blob of peak 0.9 and sigma 6 px, and a weaker blob where there is no drop. Cut at its
// IoU-best level and dilated three times the mask spills past the drop; a tighter cut is more precise.
LedHeldOutMap toy_map(const std::string& name, bool drop = true) {
  LedHeldOutMap m{name, Image(64, 48, 1, ColorSpace::kLinear), {}, drop};
  Image truth(64, 48, 1, ColorSpace::kLinear);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      const double d2 = std::pow(x + 0.5 - 20, 2) + std::pow(y + 0.5 - 24, 2);
      const double f2 = std::pow(x + 0.5 - 48, 2) + std::pow(y + 0.5 - 24, 2);
      m.attention.at(x, y) = float(0.9 * std::exp(-d2 / (2 * 36.0)) + 0.45 * std::exp(-f2 / (2 * 16.0)));
      truth.at(x, y) = drop && d2 < 64 ? 1.f : 0.f;
    }
  m.truth = {truth, truth};
  return m;
}

TEST(LedCalibrationTest, AMinimumPrecisionBoundsTheChosenRule) {
  const std::vector<LedHeldOutMap> maps{toy_map("a"), toy_map("clear", false)};
  LedCalibrationOptions o;
  o.search_peak = true;
  const LedCalibration free = calibrate_led(maps, o);
  ASSERT_TRUE(free.peak);
  EXPECT_GT(free.mean_iou, 0.5);
  EXPECT_GT(free.peak_mean_iou, 0.5);
  EXPECT_LT(free.peak_mean_precision, 0.95) << "the toy should leave room for a more precise rule";
  // The means are over the datasets with drops only: here the one drop's own score.
  EXPECT_DOUBLE_EQ(free.peak_mean_precision, free.peak_scores[0].precision);
  ASSERT_EQ(free.peak_scores.size(), 2u);

  LedCalibrationOptions bounded = o;
  bounded.min_precision = free.peak_mean_precision + 0.02;
  const LedCalibration b = calibrate_led(maps, bounded);
  ASSERT_TRUE(b.peak);
  EXPECT_GE(b.peak_mean_precision, *bounded.min_precision);
  EXPECT_GE(b.mean_precision, *bounded.min_precision);
  EXPECT_LE(b.peak_mean_iou, free.peak_mean_iou);  // a constraint never finds a higher IoU
  EXPECT_GT(b.peak_mean_iou, 0.3);

  // A bound no rule of the grid reaches (the map misses the drop: every mask is false), no drop at
  // all, nothing held out, a bound out of range: InputError.
  LedHeldOutMap missed = toy_map("missed");
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 40; ++x) missed.attention.at(x, y) = 0;
  bounded.min_precision = 0.5;
  EXPECT_THROW(calibrate_led(std::vector<LedHeldOutMap>{missed}, bounded), InputError);
  EXPECT_NO_THROW(calibrate_led(std::vector<LedHeldOutMap>{missed}, o));  // unbounded, it still picks a rule
  EXPECT_THROW(calibrate_led(std::vector<LedHeldOutMap>{toy_map("clear", false)}, o), InputError);
  EXPECT_THROW(calibrate_led(std::vector<LedHeldOutMap>{}, o), InputError);
  for (double bad : {0.0, -0.1, 1.5, std::nan("")}) {
    bounded.min_precision = bad;
    EXPECT_THROW(calibrate_led(maps, bounded), InputError) << bad;
  }
}

// A dataset of four views with two drops fixed to the lens.
void make_scene(const std::string& dir) {
  testing_util::make_drop_dataset(dir, 4, [](int w, int h, int i) {
    return testing_util::textured_view_with_drops(w, h, Rng(2, 9, uint64_t(i)), {{0.3 * w, 0.4 * h}, {0.7 * w, 0.6 * h}}, 0.12 * w);
  });
}

TEST(LedCalibrationTest, CalibrateLedReadsSavedMapsOfTheSameWeights) {
  testing::TempDir tmp;
  make_scene(tmp / "held");
  LensDetector led(tiny_arch(), 5);
  led.set_peak_rule(LedPeakRule{0.3, 0.3, 0.7});
  led.save(tmp / "w", Json::object());
  LensDetector(tiny_arch(), 6).save(tmp / "other", Json::object());
  const std::string held = tmp / "held", w = tmp / "w";
  ASSERT_EQ(run_cli("detect --data " + held + " --weights " + w + " --save-attention --out " + (tmp / "maps"), tmp / "d.log"), 0)
      << read_file(tmp / "d.log");
  ASSERT_EQ(run_cli("detect --data " + held + " --weights " + w + " --out " + (tmp / "plain"), tmp / "p.log"), 0);
  ASSERT_EQ(run_cli("detect --data " + held + " --weights " + (tmp / "other") + " --save-attention --out " + (tmp / "theirs"),
                    tmp / "o.log"), 0);

  // The saved map is the network's averaged map (to the 16-bit quantization), with the dataset's truth.
  const SavedLedMap saved = read_saved_led_map(tmp / "maps");
  const LedHeldOutMap direct = held_out_map(LensDetector::load(w), held);
  EXPECT_EQ(saved.map.name, "held");
  EXPECT_TRUE(saved.map.has_drops);
  EXPECT_TRUE(saved.adaptation.is_null());
  EXPECT_EQ(saved.weights_sha256, LensDetector::load(w).metadata().value("weights_sha256", ""));
  ASSERT_EQ(saved.map.attention.data.size(), direct.attention.data.size());
  for (size_t i = 0; i < direct.attention.data.size(); ++i)
    ASSERT_NEAR(saved.map.attention.data[i], direct.attention.data[i], 1.0 / 65535) << i;
  ASSERT_EQ(saved.map.truth.size(), direct.truth.size());
  for (size_t v = 0; v < direct.truth.size(); ++v) EXPECT_EQ(saved.map.truth[v].data, direct.truth[v].data);

  // calibrate-led --maps: the same network and blob, a calibration over the saved maps; the rule
  // `detect --adapt` uses is left alone.
  ASSERT_EQ(run_cli("calibrate-led --weights " + w + " --maps " + (tmp / "maps") + " --peak --out " + (tmp / "cal"), tmp / "c.log"), 0)
      << read_file(tmp / "c.log");
  const Json before = read_json_file(w + ".json"), after = read_json_file(tmp / "cal.json");
  EXPECT_EQ(read_file(w + ".bin"), read_file(tmp / "cal.bin"));
  EXPECT_EQ(after.at("weights_sha256"), before.at("weights_sha256"));
  EXPECT_EQ(after.at("calibration").at("held_out"), Json::array({"held"}));
  EXPECT_FALSE(after.at("calibration").contains("min_precision"));
  EXPECT_TRUE(after.contains("peak_rule"));
  EXPECT_FALSE(after.contains("adapted_peak_rule"));
  EXPECT_FALSE(LensDetector::load(tmp / "cal").adapted_peak_rule());

  // Bad input: exit 2 and nothing written.
  const std::vector<std::string> bad{
      "--maps " + (tmp / "plain") + " --peak",                              // no saved attention
      "--maps " + (tmp / "theirs") + " --peak",                             // made by other weights
      "--maps " + (tmp / "maps") + " --peak --adapted",                     // not made with --adapt
      "--maps " + (tmp / "maps") + " --adapted",                            // --adapted needs --peak
      "--maps " + (tmp / "maps") + " --held-out " + held,                   // one source of maps
      "--held-out " + held + " --adapted --peak",                           // --adapted needs --maps
      "--maps " + (tmp / "maps") + " --width 64",                           // saved maps have their width
      "--maps " + (tmp / "maps") + " --peak --min-precision 1.5",           // out of range
      "--maps " + (tmp / "nothing"),                                        // not a detect output
      "--maps " + (tmp / "maps") + " --peak --min-precision 0.01",          // the untrained network's masks are empty
  };
  // train-led calibrating on held-out datasets without drops fails before it trains: exit 2 at once.
  testing::SceneOptions so;
  so.views = 3;
  testing::make_clean_dataset(tmp / "clear", so);
  EXPECT_EQ(run_cli("train-led --data " + held + " --held-out " + (tmp / "clear") + " --out " + (tmp / "t") + " --iterations 100000",
                    tmp / "t.log"), 2) << read_file(tmp / "t.log");
  EXPECT_NE(read_file(tmp / "t.log").find("nothing to calibrate on"), std::string::npos) << read_file(tmp / "t.log");
  EXPECT_FALSE(fs::exists(tmp / "t.json"));
  for (const std::string& args : bad) {
    EXPECT_EQ(run_cli("calibrate-led --weights " + w + " " + args + " --out " + (tmp / "bad"), tmp / "b.log"), 2)
        << args << "\n" << read_file(tmp / "b.log");
    EXPECT_FALSE(fs::exists(tmp / "bad.json")) << args;
  }
}

TEST(LedCalibrationTest, TheAdaptedRuleRoundTripsAndClones) {
  testing::TempDir tmp;
  LensDetector led(tiny_arch(), 5);
  EXPECT_FALSE(led.adapted_peak_rule());
  led.set_adapted_peak_rule(LedPeakRule{0.4, 0.5, 0.85});
  EXPECT_THROW(led.set_adapted_peak_rule(LedPeakRule{0.5, 0.4, 0.5}), InputError);  // low > seed
  led.save(tmp / "w", Json::object());
  const LensDetector back = LensDetector::load(tmp / "w");
  ASSERT_TRUE(back.adapted_peak_rule());
  EXPECT_DOUBLE_EQ(back.adapted_peak_rule()->fraction, 0.85);
  EXPECT_FALSE(back.peak_rule());  // the two rules are separate
  ASSERT_TRUE(back.clone().adapted_peak_rule());
  EXPECT_DOUBLE_EQ(back.clone().adapted_peak_rule()->low, 0.4);
}

}  // namespace
}  // namespace weathergs::restoration::led
