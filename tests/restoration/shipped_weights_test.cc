// The shipped weights (models/aef, models/led) on committed fixtures of a held-out scene
// (tests/data/regression, scripts/make-regression-fixture.sh): the selector chooses rain, snow and none
// on three scenes, the AEF's plugins gain a stated number of dB, and the LED reaches a stated IoU. A
// preprocessing change that degrades the networks fails here. Inference is deterministic, so the
// floors leave room only for other CPUs' float rounding and for small intended changes.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "evaluator/metrics.h"
#include "restoration/aef/filter_dataset.h"
#include "restoration/led/detect_dataset.h"
#include "tests/core/test_util.h"

namespace weathergs::restoration {
namespace {

namespace fs = std::filesystem;
using weathergs::testing::TempDir;

const std::string kFixtures = std::string(WEATHERGS_TEST_DATA_DIR) + "/regression";
const std::string kAefWeights = std::string(WEATHERGS_SOURCE_DIR) + "/models/aef";
const std::string kLedWeights = std::string(WEATHERGS_SOURCE_DIR) + "/models/led/led";

// Floors, each about two thirds of what the shipped weights measured on these fixtures (printed by
// the tests; docs/restoration.md): far above run-to-run noise (none: inference is deterministic),
// far below what a broken input convention leaves (a swapped channel order or value range costs
// the whole gain).
constexpr double kMinDerainGainDb = 4.0;  // measured 6.39 dB (outside the drops)
constexpr double kMinDesnowGainDb = 4.0;  // measured 5.91 dB
constexpr double kMinLedIou = 0.55;       // measured 0.790 (precision 0.843, recall 0.927; drops cover 41%)

aef::FilterDatasetOptions learned(aef::AefTask task) {
  aef::FilterDatasetOptions o;
  o.method = aef::FilterMethod::kLearned;
  o.task = task;
  o.aef_weights = kAefWeights;
  return o;
}

// Mean over the dataset's views of PSNR(restored, clean) - PSNR(input, clean), outside the lens drops
// where the dataset has them (they are the LED's to find, not the AEF's to remove).
double mean_gain_db(const std::string& dataset, const std::string& restored_dir) {
  const Dataset ds = read_dataset(dataset);
  double gain = 0;
  for (const Camera& c : ds.cameras) {
    const Image clean = read_image(ds.path(ImageKind::kClean, c.name));
    const Image input = read_image(ds.path(ImageKind::kImages, c.name));
    const Image restored = read_image(restored_dir + "/" + c.name + ".png");
    const std::string lens = ds.path(ImageKind::kLensMask, c.name);
    const Image mask = fs::exists(lens) ? read_mask(lens) : Image();
    const Image* m = fs::exists(lens) ? &mask : nullptr;
    gain += evaluator::psnr(restored, clean, m) - evaluator::psnr(input, clean, m);
  }
  return gain / double(ds.cameras.size());
}

// The rain fixture with its clean renders as the inputs: a scene without weather.
std::string clear_copy(const TempDir& tmp) {
  const std::string out = tmp / "station_clear";
  copy_tree(kFixtures + "/station_rain", out);
  fs::remove_all(out + "/images");
  copy_tree(out + "/clean", out + "/images");
  fs::remove_all(out + "/masks");
  return out;
}

TEST(ShippedWeights, TheSelectorChoosesRainSnowAndNone) {
  TempDir tmp;
  const std::vector<std::pair<std::string, aef::WeatherClass>> cases = {
      {kFixtures + "/station_rain", aef::WeatherClass::kRain},
      {kFixtures + "/station_snow", aef::WeatherClass::kSnow},
      {clear_copy(tmp), aef::WeatherClass::kNone}};
  int i = 0;
  for (const auto& [dataset, expected] : cases) {
    const aef::FilterDatasetReport r = aef::filter_dataset(dataset, tmp / ("f" + std::to_string(i++)), learned(aef::AefTask::kAuto));
    ASSERT_TRUE(r.selected);
    std::printf("%s: selector chose %s (cosines rain %.3f, snow %.3f, none %.3f)\n", dataset.c_str(),
                to_string(r.scene.choice), r.scene.cosine[size_t(aef::WeatherClass::kRain)],
                r.scene.cosine[size_t(aef::WeatherClass::kSnow)], r.scene.cosine[size_t(aef::WeatherClass::kNone)]);
    EXPECT_EQ(to_string(r.scene.choice), std::string(to_string(expected))) << dataset;
  }
}

TEST(ShippedWeights, TheAefPluginsGainOnTheirWeather) {
  TempDir tmp;
  aef::filter_dataset(kFixtures + "/station_rain", tmp / "derain", learned(aef::AefTask::kDerain));
  aef::filter_dataset(kFixtures + "/station_snow", tmp / "desnow", learned(aef::AefTask::kDesnow));
  const double derain = mean_gain_db(kFixtures + "/station_rain", tmp / "derain");
  const double desnow = mean_gain_db(kFixtures + "/station_snow", tmp / "desnow");
  std::printf("derain gains %.3f dB on station_rain, desnow %.3f dB on station_snow\n", derain, desnow);
  EXPECT_GE(derain, kMinDerainGainDb);
  EXPECT_GE(desnow, kMinDesnowGainDb);
}

TEST(ShippedWeights, TheLedFindsTheDropsOfARainyScene) {
  TempDir tmp;
  led::DetectDatasetOptions o;
  o.weights = kLedWeights;
  const led::DetectDatasetReport r = led::detect_dataset(kFixtures + "/station_rain", tmp / "detected", o);
  ASSERT_TRUE(r.ground_truth.has_value()) << "the fixture has masks/lens";
  std::printf("LED on station_rain: IoU %.3f, precision %.3f, recall %.3f (drops cover %.3f of the pixels)\n",
              r.ground_truth->iou, r.ground_truth->precision, r.ground_truth->recall, r.ground_truth->gt_fraction);
  EXPECT_GE(r.ground_truth->iou, kMinLedIou);
}

}  // namespace
}  // namespace weathergs::restoration
