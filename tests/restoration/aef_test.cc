// The learned AEF (restoration/aef/aef_plugin.h), the weather selector (restoration/aef/weather_selector.h),
// their training, and `weathergs filter --method learned`.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <set>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/json_reader.h"
#include "core/parallel.h"
#include "core/rng.h"
#include "restoration/aef/aef_training.h"
#include "restoration/aef/filter_dataset.h"
#include "tests/core/test_util.h"
#include "tests/restoration/restoration_test_util.h"
#include "tests/generator/test_scene.h"

namespace weathergs::restoration::aef {
namespace {

namespace fs = std::filesystem;

// A textured background; `rain` draws bright vertical streaks (1 px wide), `snow` bright 2x2 flakes.
// target = the background, alpha = where the particles are.
AefExample toy_view(int w, int h, uint64_t seed, int index, WeatherClass weather) {
  AefExample e{Image(w, h, 3), Image(w, h, 3), Image(w, h, 1, ColorSpace::kLinear)};
  Rng rng(seed, 11, uint64_t(index));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) e.image.at(x, y, c) = e.target.at(x, y, c) = 0.25f + 0.15f * float((x / 4 + y / 4 + c) % 3) / 2;
  const int n = weather == WeatherClass::kNone ? 0 : w * h / 60;
  for (int k = 0; k < n; ++k) {
    const int x0 = int(rng.uniform_int(uint32_t(w))), y0 = int(rng.uniform_int(uint32_t(h)));
    const int len = weather == WeatherClass::kRain ? 6 : 2, wid = weather == WeatherClass::kRain ? 1 : 2;
    for (int dy = 0; dy < len; ++dy)
      for (int dx = 0; dx < wid; ++dx) {
        const int x = x0 + dx, y = y0 + dy;
        if (x >= w || y >= h) continue;
        e.alpha.at(x, y) = 1;
        for (int c = 0; c < 3; ++c) e.image.at(x, y, c) = 0.95f;
      }
  }
  return e;
}

AefArchitecture tiny_arch() {
  AefArchitecture a;
  a.channels = 4;
  a.bottleneck = 8;
  a.residual_blocks = 1;
  a.prior_gain = 0;  // the network alone: training must do all the work
  return a;
}

AefTrainOptions tiny_options() {
  AefTrainOptions o;
  o.arch = tiny_arch();
  o.iterations = 120;
  o.batch = 4;
  o.crop = 32;
  o.learning_rate = 5e-3;
  o.threads = 1;  // 2 libtorch threads on a loaded 2-core machine spin: 10x slower
  o.progress = false;
  return o;
}

TEST(AefPluginTest, ShapesRangeAndParameterCount) {
  const AefArchitecture a;  // the shipped architecture
  const AefPlugin p(AefPluginKind::kDerain, a, 1);
  // e0 7->c, e1 c->2c (stride 2), e2 2c->B (stride 2), blocks 2 convs B->B each, d1 B+2c->2c, d0 2c+c->c
  // (3x3 kernels + biases), head c->4 (1x1).
  const int64_t c = a.channels, b = a.bottleneck;
  const int64_t expect = (7 * c * 9 + c) + (c * 2 * c * 9 + 2 * c) + (2 * c * b * 9 + b) + a.residual_blocks * 2 * (b * b * 9 + b) +
                         ((b + 2 * c) * 2 * c * 9 + 2 * c) + (3 * c * c * 9 + c) + (c * 4 + 4);
  EXPECT_EQ(p.parameter_count(), expect);
  EXPECT_LT(p.parameter_count(), 300000);  // the size budget: a few hundred thousand at most
  for (auto [w, h] : {std::pair{90, 61}, std::pair{33, 17}}) {  // odd sizes: the decoder meets its skips
    const AefExample e = toy_view(w, h, 3, 0, WeatherClass::kRain);
    const AefOutput out = p.restore(e.image, "toy");
    EXPECT_EQ(out.restored.width, w);
    EXPECT_EQ(out.restored.height, h);
    EXPECT_EQ(out.restored.channels, 3);
    EXPECT_EQ(out.alpha.channels, 1);
    for (float v : out.alpha.data) ASSERT_TRUE(v >= 0 && v <= 1) << v;
    for (float v : out.restored.data) ASSERT_TRUE(v >= 0 && v <= 1) << v;
  }
  // RGBA gives the same output as its RGB part.
  const AefExample e = toy_view(40, 30, 3, 1, WeatherClass::kSnow);
  Image rgba(40, 30, 4);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) {
      for (int k = 0; k < 3; ++k) rgba.at(x, y, k) = e.image.at(x, y, k);
      rgba.at(x, y, 3) = 1;
    }
  EXPECT_EQ(p.restore(rgba, "rgba").restored.data, p.restore(e.image, "rgb").restored.data);

  const WeatherSelector s(SelectorArchitecture{}, 1);
  const std::vector<float> emb = s.embed(e.image, "toy");
  EXPECT_EQ(int(emb.size()), SelectorArchitecture{}.embedding);
  double n2 = 0;
  for (float v : emb) n2 += double(v) * v;
  EXPECT_NEAR(n2, 1.0, 1e-5);
}

TEST(AefPluginTest, TinyTrainingReducesTheLossAndRemovesStreaks) {
  std::vector<AefExample> set;
  for (int i = 0; i < 6; ++i) set.push_back(toy_view(64, 48, 5, i, i % 3 == 2 ? WeatherClass::kNone : WeatherClass::kRain));
  AefPlugin p(AefPluginKind::kDerain, tiny_arch(), 2);
  const AefTrainOptions o = tiny_options();
  const double before = p.loss(set, o);
  const AefTrainRecord rec = p.train(set, o);
  const double after = p.loss(set, o);
  EXPECT_LT(after, 0.6 * before) << before << " -> " << after;
  EXPECT_FALSE(rec.loss_curve.empty());
  // A new view: the output is closer to the target than the input.
  const AefExample probe = toy_view(64, 48, 77, 0, WeatherClass::kRain);
  const Image out = p.restore(probe.image, "probe").restored;
  double err_in = 0, err_out = 0;
  for (size_t i = 0; i < out.data.size(); ++i) {
    err_in += std::abs(probe.image.data[i] - probe.target.data[i]);
    err_out += std::abs(out.data[i] - probe.target.data[i]);
  }
  EXPECT_LT(err_out, 0.7 * err_in) << err_in << " -> " << err_out;
}

TEST(AefPluginTest, TrainingWithOneThreadIsReproducible) {
  std::vector<AefExample> set;
  for (int i = 0; i < 3; ++i) set.push_back(toy_view(48, 40, 8, i, WeatherClass::kSnow));
  AefTrainOptions o = tiny_options();
  o.iterations = 15;
  o.threads = 1;
  SelectorTrainOptions so;
  so.arch.width = 48;
  so.arch.channels = 4;
  so.arch.embedding = 4;
  so.iterations = 10;
  so.batch = 4;
  so.threads = 1;
  so.progress = false;
  std::vector<SelectorExample> sel;
  for (int i = 0; i < 3; ++i) sel.push_back({set[size_t(i)].image, WeatherClass(i)});
  testing::TempDir tmp;
  for (const std::string stem : {"a", "b"}) {
    AefPlugin p(AefPluginKind::kDesnow, tiny_arch(), 3);
    p.train(set, o);
    p.save(tmp / stem, Json::object());
    WeatherSelector s(so.arch, 3);
    s.train(sel, so);
    s.save(tmp / ("s" + stem), Json::object());
  }
  EXPECT_EQ(read_file(tmp / "a.bin"), read_file(tmp / "b.bin"));
  EXPECT_EQ(read_file(tmp / "sa.bin"), read_file(tmp / "sb.bin"));
}

TEST(AefPluginTest, SaveLoadRoundTripAndThreadCountInvariance) {
  testing::TempDir tmp;
  const AefPlugin p(AefPluginKind::kDesnow, AefArchitecture{}, 4);
  p.save(tmp / "w", Json{{"note", "test"}});
  const AefPlugin back = AefPlugin::load(tmp / "w", AefPluginKind::kDesnow);
  EXPECT_EQ(back.metadata().at("note"), "test");
  WeatherSelector s(SelectorArchitecture{}, 4);
  s.set_theta(0.37);
  s.save(tmp / "s", Json::object());
  const WeatherSelector sback = WeatherSelector::load(tmp / "s");
  EXPECT_DOUBLE_EQ(sback.theta(), 0.37);
  const AefExample e = toy_view(150, 100, 6, 0, WeatherClass::kSnow);
  const int before = num_threads();
  set_num_threads(1);
  const AefOutput a1 = p.restore(e.image, "t1"), b1 = back.restore(e.image, "t1");
  const std::vector<float> e1 = s.embed(e.image, "t1"), f1 = sback.embed(e.image, "t1");
  set_num_threads(2);
  const AefOutput a2 = p.restore(e.image, "t2");
  const std::vector<float> e2 = s.embed(e.image, "t2");
  set_num_threads(before);
  EXPECT_EQ(a1.restored.data, b1.restored.data);  // bit-identical after the round trip
  EXPECT_EQ(a1.restored.data, a2.restored.data);  // and with 1 or 2 threads
  EXPECT_EQ(a1.alpha.data, a2.alpha.data);
  EXPECT_EQ(e1, f1);
  EXPECT_EQ(e1, e2);
}

TEST(AefPluginTest, BadWeightsAndInputsAreInputErrors) {
  testing::TempDir tmp;
  EXPECT_THROW(AefPlugin::load(tmp / "missing", AefPluginKind::kDerain), InputError);
  EXPECT_THROW(WeatherSelector::load(tmp / "missing"), InputError);
  const AefPlugin p(AefPluginKind::kDerain, tiny_arch(), 1);
  p.save(tmp / "w", Json::object());
  std::string blob = read_file(tmp / "w.bin");
  blob[10] ^= 0x5a;
  write_file_atomic(tmp / "c.bin", blob);
  fs::copy_file(tmp / "w.json", tmp / "c.json");
  try {
    AefPlugin::load(tmp / "c", AefPluginKind::kDerain);
    FAIL() << "corrupt weights loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("c.bin"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("make models"), std::string::npos) << e.what();
  }
  // The derain weights are not desnow weights, nor a selector.
  EXPECT_THROW(AefPlugin::load(tmp / "w", AefPluginKind::kDesnow), InputError);
  EXPECT_THROW(WeatherSelector::load(tmp / "w"), InputError);
  const Json j = read_json_file(tmp / "w.json");
  auto variant = [&](const std::string& stem, const std::function<void(Json&)>& edit, bool copy_bin = true) {
    Json k = j;
    edit(k);
    write_file_atomic(tmp / (stem + ".json"), k.dump());
    if (copy_bin) fs::copy_file(tmp / "w.bin", tmp / (stem + ".bin"));
    EXPECT_THROW(AefPlugin::load(tmp / stem, AefPluginKind::kDerain), InputError) << stem;
  };
  variant("f", [](Json& k) { k["format"] = "weathergs-led"; });
  variant("v", [](Json& k) { k["version"] = 99; });
  variant("b", [](Json&) {}, false);
  variant("a", [](Json& k) { k["architecture"]["channels"] = 7; });
  variant("x", [](Json& k) { k["architecture"]["unknown"] = 1; });
  // Images: grey, too small, non-finite.
  EXPECT_THROW(p.restore(Image(40, 30, 1), "grey"), InputError);
  EXPECT_THROW(p.restore(Image(4, 4, 3), "tiny"), InputError);
  Image nan(40, 30, 3);
  nan.data[5] = std::nanf("");
  EXPECT_THROW(p.restore(nan, "nan"), InputError);
  // Options name their field.
  AefTrainOptions t;
  t.crop = 4;
  try {
    t.validate();
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("crop"), std::string::npos) << e.what();
  }
  FilterDatasetOptions f;
  f.method = FilterMethod::kLearned;  // "always" has no learned plugin
  EXPECT_THROW(f.validate(), InputError);
}

TEST(WeatherSelectorTest, InstructionsAndTheThetaRule) {
  EXPECT_EQ(class_of_instruction("Remove snowy effect in the scene"), WeatherClass::kSnow);
  EXPECT_EQ(class_of_instruction("  remove rainy effect in the scene. "), WeatherClass::kRain);
  EXPECT_EQ(class_of_instruction("Remove rainy effect in the scene"), WeatherClass::kRain);
  EXPECT_EQ(class_of_instruction("none"), WeatherClass::kNone);
  EXPECT_EQ(class_of_instruction("please remove the snow"), WeatherClass::kSnow);
  EXPECT_THROW(class_of_instruction("make it sunny"), InputError);
  EXPECT_THROW(class_of_instruction("rain and snow"), InputError);
  const WeatherSelector s(SelectorArchitecture{}, 5);
  const std::vector<float> e = s.embed(toy_view(96, 64, 1, 0, WeatherClass::kRain).image, "e");
  const Selection lo = s.select(e, -1.0), hi = s.select(e, 1.01);
  EXPECT_EQ(hi.choice, WeatherClass::kNone);  // no cosine reaches theta > 1
  const double best_plugin = std::max(lo.cosine[0], lo.cosine[1]);
  EXPECT_EQ(lo.choice == WeatherClass::kNone, best_plugin <= lo.cosine[2]);
  const std::vector<float> m = WeatherSelector::mean_embedding({e, e});
  for (size_t i = 0; i < e.size(); ++i) EXPECT_NEAR(m[i], e[i], 1e-6);
}

TEST(WeatherSelectorTest, TinyTrainingSeparatesRainSnowAndClear) {
  std::vector<SelectorExample> set;
  for (int i = 0; i < 24; ++i) set.push_back({toy_view(96, 64, 9, i, WeatherClass(i % 3)).image, WeatherClass(i % 3)});
  SelectorTrainOptions o;
  o.arch.width = 96;
  o.arch.channels = 8;
  o.arch.embedding = 8;
  o.iterations = 150;
  o.batch = 12;
  o.learning_rate = 3e-3;
  o.threads = 1;  // 2 libtorch threads on a loaded 2-core machine spin: 10x slower
  o.progress = false;
  WeatherSelector s(o.arch, 6);
  const SelectorTrainRecord rec = s.train(set, o);
  EXPECT_LT(rec.loss_curve.back(), 0.5 * rec.loss_curve.front()) << rec.loss_curve.front() << " -> " << rec.loss_curve.back();
  s.set_theta(-1.0);  // the argmax of the three cosines: what the embedding separates, before calibration
  int right = 0;
  for (int i = 0; i < 12; ++i) right += s.select(s.embed(toy_view(96, 64, 123, i, WeatherClass(i % 3)).image, "p")).choice == WeatherClass(i % 3);
  EXPECT_GE(right, 11);
}

using testing_util::run_cli;

TEST(FilterLearnedTest, TasksOverridesReportAndBadInput) {
  testing::TempDir tmp;
  testing::SceneOptions so;
  so.views = 3;
  testing::make_clean_dataset(tmp / "d", so);
  fs::create_directories(tmp / "w");
  AefPlugin(AefPluginKind::kDerain, tiny_arch(), 1).save(tmp / "w/derain", Json::object());
  AefPlugin(AefPluginKind::kDesnow, tiny_arch(), 2).save(tmp / "w/desnow", Json::object());
  WeatherSelector sel(SelectorArchitecture{}, 3);
  sel.set_theta(1.0);  // no cosine can pass: auto must choose none
  sel.save(tmp / "w/selector", Json::object());
  const std::string data = "filter --data " + (tmp / "d") + " --images clean ";
  const std::string base = data + "--weights " + (tmp / "w") + " ";
  auto plugins = [&](const std::string& out) {
    std::set<std::string> s;
    const Json j = read_json_file(tmp / (out + "/filter.json"));
    for (const Json& v : j.at("views")) s.insert(v.at("plugin").get<std::string>());
    return s;
  };
  ASSERT_EQ(run_cli(base + "--task derain --out " + (tmp / "r"), tmp / "1.log"), 0) << read_file(tmp / "1.log");
  EXPECT_EQ(plugins("r"), std::set<std::string>{"derain"});
  ASSERT_EQ(run_cli(base + "--task desnow --mode mask --out " + (tmp / "s"), tmp / "2.log"), 0) << read_file(tmp / "2.log");
  EXPECT_EQ(plugins("s"), std::set<std::string>{"desnow"});
  ASSERT_EQ(run_cli(base + "--instruction 'Remove snowy effect in the scene' --out " + (tmp / "i"), tmp / "3.log"), 0);
  EXPECT_EQ(plugins("i"), std::set<std::string>{"desnow"});
  EXPECT_EQ(read_json_file(tmp / "i/filter.json").at("instruction"), "Remove snowy effect in the scene");
  ASSERT_EQ(run_cli(base + "--task auto --select per-view --out " + (tmp / "a"), tmp / "4.log"), 0) << read_file(tmp / "4.log");
  EXPECT_EQ(plugins("a"), std::set<std::string>{"none"});
  const Json a = read_json_file(tmp / "a/filter.json");
  EXPECT_EQ(a.at("selection").at("scope"), "per-view");
  EXPECT_EQ(a.at("selection").at("theta"), 1.0);
  EXPECT_TRUE(a.at("views")[0].contains("cosine"));
  const Dataset ds = read_dataset(tmp / "d");
  for (const Camera& c : ds.cameras) {  // none: the view is left exactly as it was
    EXPECT_EQ(read_image(tmp / ("a/" + c.name + ".png")).data, read_image(ds.path(ImageKind::kClean, c.name)).data);
    EXPECT_TRUE(fs::exists(tmp / ("r/masks/" + c.name + ".png")));
  }
  // 1 and 2 threads: the same bytes.
  ASSERT_EQ(run_cli("--threads 1 " + base + "--task derain --out " + (tmp / "t1"), tmp / "5.log"), 0);
  ASSERT_EQ(run_cli("--threads 2 " + base + "--task derain --out " + (tmp / "t2"), tmp / "6.log"), 0);
  for (const Camera& c : ds.cameras) EXPECT_EQ(read_file(tmp / ("t1/" + c.name + ".png")), read_file(tmp / ("t2/" + c.name + ".png")));
  // Bad input: exit 2, the file named, nothing written.
  EXPECT_EQ(run_cli(data + "--task derain --weights " + (tmp / "nope") + " --out " + (tmp / "g"), tmp / "b1.log"), 2);
  EXPECT_NE(read_file(tmp / "b1.log").find("nope/derain.json"), std::string::npos) << read_file(tmp / "b1.log");
  EXPECT_EQ(run_cli(base + "--instruction 'make it sunny' --out " + (tmp / "g"), tmp / "b2.log"), 2);
  EXPECT_EQ(run_cli(base + "--method learned --task always --out " + (tmp / "g"), tmp / "b3.log"), 2);
  std::string blob = read_file(tmp / "w/desnow.bin");
  blob[3] ^= 0x11;
  write_file_atomic(tmp / "w/desnow.bin", blob);
  EXPECT_EQ(run_cli(base + "--task auto --out " + (tmp / "g"), tmp / "b4.log"), 2);
  EXPECT_NE(read_file(tmp / "b4.log").find("desnow.bin"), std::string::npos) << read_file(tmp / "b4.log");
  // A view of the wrong size.
  const Image small(20, 20, 3);
  write_image(ds.path(ImageKind::kClean, ds.cameras[1].name), small);
  EXPECT_EQ(run_cli(base + "--task derain --out " + (tmp / "g"), tmp / "b5.log"), 2);
  EXPECT_NE(read_file(tmp / "b5.log").find(ds.cameras[1].name + ".png"), std::string::npos) << read_file(tmp / "b5.log");
  EXPECT_FALSE(fs::exists(tmp / "g"));
}

}  // namespace
}  // namespace weathergs::restoration::aef
