// The LED's pooling over the views of one dataset (LedViewPooling, docs/record/led_variants.md, "Pooling
// over the views"): what a pooled network shares between the views of a call, how it trains on
// groups, its weights format, and `detect` running it on the dataset's views together.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/json_reader.h"
#include "core/rng.h"
#include "restoration/led/detect_dataset.h"
#include "restoration/led/lens_detector.h"
#include "tests/core/test_util.h"
#include "tests/restoration/restoration_test_util.h"

namespace weathergs::restoration::led {
namespace {

namespace fs = std::filesystem;

// A textured view (texture keyed on `index`: the scene moves between views) with two blurry bright
// discs at places keyed on `layout` only (drops fixed to the lens), and their mask.
LedExample lens_view(int w, int h, int layout, int index) {
  LedExample e = testing_util::textured_view_with_drops(
      w, h, Rng(11, uint64_t(layout), uint64_t(index)), {{(0.25 + 0.1 * layout) * w, 0.4 * h}, {0.7 * w, (0.5 + 0.05 * layout) * h}},
      0.12 * w);
  e.group = layout;
  return e;
}

LedArchitecture tiny_arch(LedViewPooling pooling) {
  LedArchitecture a = testing_util::tiny_arch();
  a.view_pooling = pooling;
  return a;
}

float max_abs_difference(const Image& a, const Image& b) {
  float m = 0;
  for (size_t i = 0; i < a.data.size(); ++i) m = std::max(m, std::abs(a.data[i] - b.data[i]));
  return m;
}

TEST(LedViewPoolingTest, PooledNetworksShareTheViewsOfACallAndIgnoreTheirOrder) {
  std::vector<LedExample> set;
  for (int i = 0; i < 4; ++i) set.push_back(lens_view(64, 48, 0, i));
  // The call: a view of texture only, then two views that share the drops.
  std::vector<Image> views{Image(64, 48, 3), set[1].image, set[2].image};
  Rng rng(3, 0, 0);
  for (float& v : views[0].data) v = 0.2f + 0.3f * rng.uniform();
  LedTrainOptions o;
  o.threads = 1;
  o.iterations = 40;
  o.batch = 4;
  o.learning_rate = 3e-3;
  o.progress = false;
  // Without pooling a view's map does not depend on the other views of the call (up to the float
  // rounding of another batch size in libtorch's convolutions).
  o.arch = tiny_arch(LedViewPooling::kNone);
  LensDetector plain(o.arch, 5);
  plain.train(set, o);
  const float plain_shift = max_abs_difference(plain.attention(views, "plain")[0], plain.attention(views[0], "plain"));
  EXPECT_LT(plain_shift, 1e-5f);
  for (LedViewPooling p : {LedViewPooling::kAttention, LedViewPooling::kAttentionAndState}) {
    o.arch = tiny_arch(p);
    LensDetector led(o.arch, 5);
    led.train(set, o);
    const std::vector<Image> together = led.attention(views, "pooled");
    EXPECT_GT(max_abs_difference(together[0], led.attention(views[0], "alone")), 1e-3f) << to_string(p);
    // The pooled quantity is a mean: the order of the other views does not matter (up to the float
    // summation order of the mean, far below the 8-bit PNG step of a saved map).
    const std::vector<Image> reordered = led.attention({views[0], views[2], views[1]}, "reordered");
    EXPECT_LT(max_abs_difference(together[0], reordered[0]), 1e-5f) << to_string(p);
    for (float v : together[1].data) ASSERT_TRUE(v >= 0 && v <= 1) << v;
  }
  // Parameters: the first conv reads one more channel (the mean attention), the ConvLSTM's gates C more.
  const int64_t c = 6;
  const int64_t plain_count = LensDetector(tiny_arch(LedViewPooling::kNone), 1).parameter_count();
  EXPECT_EQ(LensDetector(tiny_arch(LedViewPooling::kAttention), 1).parameter_count(), plain_count + c * 9);
  EXPECT_EQ(LensDetector(tiny_arch(LedViewPooling::kAttentionAndState), 1).parameter_count(),
            plain_count + c * 9 + c * 4 * c * 9);
}

TEST(LedViewPoolingTest, TrainsOnGroupsReproduciblyAndReducesTheLoss) {
  std::vector<LedExample> set;
  for (int layout = 0; layout < 2; ++layout)
    for (int i = 0; i < 4; ++i) set.push_back(lens_view(64, 48, layout, i));
  LedTrainOptions o;
  o.arch = tiny_arch(LedViewPooling::kAttentionAndState);
  o.iterations = 150;
  o.batch = 4;
  o.learning_rate = 3e-3;
  o.threads = 1;
  o.progress = false;
  testing::TempDir tmp;
  for (const char* stem : {"a", "b"}) {
    LensDetector led(o.arch, 2);
    const std::vector<LedExample> group0(set.begin(), set.begin() + 4);
    const double before = led.loss(group0, 0.8);
    led.train(set, o);
    EXPECT_LT(led.loss(group0, 0.8), 0.5 * before) << stem;
    led.save(tmp / stem, Json::object());
  }
  EXPECT_EQ(read_file(tmp / "a.bin"), read_file(tmp / "b.bin"));  // one thread: the same weights
  // A group with fewer views than the batch cannot fill one: an error naming the group.
  set.pop_back();
  LensDetector led(o.arch, 2);
  try {
    led.train(set, o);
    FAIL() << "a 3-view group trained with batch 4";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("group 1"), std::string::npos) << e.what();
  }
}

TEST(LedViewPoolingTest, WeightsRecordThePoolingAndDetectRunsTheViewsTogether) {
  testing::TempDir tmp;
  const LensDetector led(tiny_arch(LedViewPooling::kAttention), 3);
  led.save(tmp / "w", Json::object());
  const Json j = read_json_file(tmp / "w.json");
  EXPECT_EQ(j.at("architecture").at("view_pooling"), "attention");
  const LensDetector back = LensDetector::load(tmp / "w");
  EXPECT_EQ(back.architecture().view_pooling, LedViewPooling::kAttention);
  // A per-view network's JSON has no view_pooling key (weights saved before it read as before).
  LensDetector(tiny_arch(LedViewPooling::kNone), 3).save(tmp / "n", Json::object());
  EXPECT_FALSE(read_json_file(tmp / "n.json").at("architecture").contains("view_pooling"));
  {  // An unknown pooling is an error naming the key.
    Json k = j;
    k["architecture"]["view_pooling"] = "median";
    write_file_atomic(tmp / "bad.json", k.dump());
    fs::copy_file(tmp / "w.bin", tmp / "bad.bin");
    try {
      LensDetector::load(tmp / "bad");
      FAIL() << "an unknown view_pooling loaded";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("view_pooling"), std::string::npos) << e.what();
    }
  }
  // mean_attention runs a pooled network on all views in one call, whatever batch it is asked for:
  // the same map as the network's own call over the views, averaged in view order.
  std::vector<Image> views;
  for (int i = 0; i < 5; ++i) views.push_back(lens_view(64, 48, 1, i).image);
  const std::vector<Image> maps = back.attention(views, "views");
  Image expect(64, 48, 1, ColorSpace::kLinear);
  for (const Image& m : maps)
    for (size_t i = 0; i < expect.data.size(); ++i) expect.data[i] += m.data[i];
  for (float& v : expect.data) v /= 5.f;
  EXPECT_EQ(mean_attention(back, views, "views", 1).data, expect.data);
  EXPECT_EQ(mean_attention(back, views, "views", 2).data, expect.data);
}

using testing_util::run_cli;

// A dataset whose views carry the drops of `layout` (the same on every view) and masks/lens/ their masks.
void make_drop_dataset(const std::string& dir, int views, int layout) {
  testing_util::make_drop_dataset(dir, views, [layout](int w, int h, int i) { return lens_view(w, h, layout, i); });
}

TEST(LedViewPoolingTest, TrainLedAndDetectFromTheCommandLine) {
  testing::TempDir tmp;
  make_drop_dataset(tmp / "a", 6, 0);
  make_drop_dataset(tmp / "b", 6, 1);
  make_drop_dataset(tmp / "held", 8, 2);
  const std::string data = " --data " + (tmp / "a") + " " + (tmp / "b") + " --held-out " + (tmp / "held");
  ASSERT_EQ(run_cli("train-led" + data + " --out " + (tmp / "w") +
                        " --iterations 30 --batch 4 --width 48 --channels 6 --steps 2 --view-pooling attention+state",
                    tmp / "t.log"), 0)
      << read_file(tmp / "t.log");
  EXPECT_EQ(read_json_file(tmp / "w.json").at("architecture").at("view_pooling"), "attention+state");
  ASSERT_EQ(run_cli("detect --data " + (tmp / "held") + " --weights " + (tmp / "w") + " --out " + (tmp / "m"), tmp / "d.log"), 0)
      << read_file(tmp / "d.log");
  EXPECT_TRUE(read_json_file(tmp / "m/detect.json").at("ground_truth").contains("iou"));
  // An unknown pooling and a batch larger than a dataset's views are usage / input errors (exit 2),
  // nothing written.
  EXPECT_EQ(run_cli("train-led" + data + " --out " + (tmp / "x") + " --view-pooling median", tmp / "x.log"), 2);
  EXPECT_EQ(run_cli("train-led" + data + " --out " + (tmp / "x") + " --iterations 5 --batch 7 --view-pooling attention",
                    tmp / "y.log"), 2)
      << read_file(tmp / "y.log");
  EXPECT_FALSE(fs::exists(tmp / "x.json"));
}

}  // namespace
}  // namespace weathergs::restoration::led
