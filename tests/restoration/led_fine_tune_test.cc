// `weathergs train-led --init` (fine-tune given weights) and `--ignore-mask` (restoration/led/led_training.h):
// the training path of the LED's test-time adaptation (adaptation/led_adaptation.h).
#include <gtest/gtest.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/json_reader.h"
#include "restoration/led/led_training.h"
#include "tests/core/test_util.h"
#include "tests/restoration/restoration_test_util.h"

namespace weathergs::restoration::led {
namespace {

namespace fs = std::filesystem;
using testing_util::run_cli;
using testing_util::tiny_arch;

// train-led --init fine-tunes given weights (keeping their calibration); --ignore-mask leaves its
// pixels out of the loss unless a drop is there. With every pixel ignored only the drops count, so
// the network learns to mark everything: the background's attention rises far above that of the
// same fine-tune without the mask.
TEST(LedFineTuneTest, TrainLedInitFineTunesAndTheIgnoreMaskLeavesPixelsOut) {
  testing::TempDir tmp;
  testing_util::make_drop_dataset(tmp / "train", 4, [](int w, int h, int i) {
    return testing_util::textured_view_with_drops(w, h, Rng(1, 7, uint64_t(i)), {{0.3 * w, 0.4 * h}, {0.7 * w, 0.6 * h}}, 0.12 * w);
  });
  LensDetector base(tiny_arch(), 3);
  base.set_threshold(0.3);
  base.save(tmp / "base", Json::object());
  const Dataset ds = read_dataset(tmp / "train");
  const Camera& c = ds.cameras[0];
  write_mask(tmp / "all.png", Image(c.width, c.height, 1, ColorSpace::kLinear, 1.f));
  write_mask(tmp / "small.png", Image(c.width / 2, c.height, 1, ColorSpace::kLinear, 1.f));
  TrainLedOptions o;
  o.train.iterations = 40;
  o.train.batch = 2;
  o.train.learning_rate = 0.01;
  o.train.threads = 1;
  o.train.progress = false;
  o.init = tmp / "base";
  train_led({tmp / "train"}, {}, tmp / "plain", o);
  o.ignore_mask = tmp / "all.png";
  train_led({tmp / "train"}, {}, tmp / "ignored", o);
  const LensDetector plain = LensDetector::load(tmp / "plain"), ignored = LensDetector::load(tmp / "ignored");
  EXPECT_DOUBLE_EQ(plain.threshold(), 0.3);  // the init's calibration is kept without --held-out
  EXPECT_EQ(plain.architecture().width, tiny_arch().width);
  const Image view = read_image(ds.path(ImageKind::kImages, c.name));
  const Image truth = read_mask(ds.path(ImageKind::kLensMask, c.name));
  auto background_mean = [&](const LensDetector& led) {
    const Image a = led.attention(view, "view");
    double sum = 0, n = 0;
    for (size_t i = 0; i < a.data.size(); ++i)
      if (truth.data[i] == 0) sum += a.data[i], n += 1;
    return sum / n;
  };
  EXPECT_GT(background_mean(ignored), background_mean(plain) + 0.2);
  // A mask of another size than the views: exit 2 naming it, no weights written.
  EXPECT_EQ(run_cli("train-led --data " + (tmp / "train") + " --init " + (tmp / "base") + " --ignore-mask " + (tmp / "small.png") +
                        " --iterations 2 --out " + (tmp / "bad"),
                    tmp / "bad.log"),
            2);
  EXPECT_NE(read_file(tmp / "bad.log").find("small.png"), std::string::npos) << read_file(tmp / "bad.log");
  EXPECT_FALSE(fs::exists(tmp / "bad.json"));
}

}  // namespace
}  // namespace weathergs::restoration::led
