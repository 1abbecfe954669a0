// Whole radiance-field runs (nerf/run.h): a finished field is reused only by a run that asks for the
// settings it records (the data and every option, the seed included); any other setting makes it
// stale, named, so that methods/ refuses it instead of passing an old field off as a new one. A run
// stopped part way resumes from its checkpoint to the same bits.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <map>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_reader.h"
#include "nerf/run.h"
#include "tests/core/test_util.h"
#include "tests/generator/test_scene.h"

namespace weathergs::nerf {
namespace {

namespace fs = std::filesystem;

// A field small and short enough to train in about a second.
NerfOptions tiny_options() {
  NerfOptions o;
  o.iterations = 6;
  o.batch_rays = 256;
  o.seed = 4;
  o.pixels_per_cell = 4;
  o.depth_cells = 8;
  o.level_scales = {1.0};
  o.upsample_at = {};
  return o;
}

// Another valid value for every NerfOptions key (run.json's "options"): what the test varies.
std::map<std::string, std::function<void(NerfOptions&)>> one_change_per_key() {
  return {
      {"iterations", [](NerfOptions& o) { o.iterations = 7; }},
      {"batch_rays", [](NerfOptions& o) { o.batch_rays = 128; }},
      {"seed", [](NerfOptions& o) { o.seed = 5; }},
      {"pixels_per_cell", [](NerfOptions& o) { o.pixels_per_cell = 3; }},
      {"depth_cells", [](NerfOptions& o) { o.depth_cells = 10; }},
      {"level_scales", [](NerfOptions& o) { o.level_scales = {0.5, 1.0}, o.upsample_at = {3}; }},
      {"upsample_at", [](NerfOptions& o) { o.upsample_at = {3}, o.level_scales = {0.5, 1.0}; }},
      {"alpha_init", [](NerfOptions& o) { o.alpha_init = 0.02; }},
      {"lr_density", [](NerfOptions& o) { o.lr_density = 0.2; }},
      {"lr_color", [](NerfOptions& o) { o.lr_color = 0.2; }},
      {"lr_env", [](NerfOptions& o) { o.lr_env = 0.1; }},
      {"lr_final_factor", [](NerfOptions& o) { o.lr_final_factor = 0.5; }},
      {"tv_density", [](NerfOptions& o) { o.tv_density = 1e-4; }},
      {"tv_color", [](NerfOptions& o) { o.tv_color = 1e-4; }},
      {"tv_fraction", [](NerfOptions& o) { o.tv_fraction = 0.02; }},
      {"near_m", [](NerfOptions& o) { o.near_m = 1.5; }},
      {"samples_per_cell", [](NerfOptions& o) { o.march.samples_per_cell = 3; }},
      {"min_weight", [](NerfOptions& o) { o.march.min_weight = 1e-3f; }},
      {"min_transmittance", [](NerfOptions& o) { o.march.min_transmittance = 1e-3f; }},
  };
}

// A tiny clean dataset in tmp/data and a run of tiny_options on it.
NerfRunOptions tiny_run(const weathergs::testing::TempDir& tmp) {
  weathergs::testing::SceneOptions so;
  so.views = 4;
  so.width = 48, so.height = 32, so.fx = 40;
  weathergs::testing::make_clean_dataset(tmp / "data", so);
  copy_tree(tmp / "data/clean", tmp / "data/images");
  NerfRunOptions o;
  o.dataset = tmp / "data";
  o.out = tmp / "run";
  o.nerf = tiny_options();
  return o;
}

TEST(NerfRunTest, AFinishedFieldIsReusedOnlyWithEverySettingItRecords) {
  weathergs::testing::TempDir tmp;
  NerfRunOptions o = tiny_run(tmp);
  // Before and while training nothing is reusable; an incomplete run of the same settings starts over.
  EXPECT_EQ(nerf_run_output(o.out, o.dataset, o.inputs, o.nerf).state, StageOutput::State::kAbsent);
  const NerfRunResult trained = train_nerf_run(o);
  // The training's CPU seconds are recorded beside its wall seconds.
  ASSERT_TRUE(trained.train_cpu_seconds.has_value());
  EXPECT_GT(*trained.train_cpu_seconds, 0);
  EXPECT_EQ(read_json_file(o.out + "/run.json").at("train_cpu_seconds").get<double>(), *trained.train_cpu_seconds);
  const StageOutput same = nerf_run_output(o.out, o.dataset, o.inputs, o.nerf);
  EXPECT_EQ(same.state, StageOutput::State::kComplete) << same.why;
  // The same folder named another way is the same data.
  EXPECT_EQ(nerf_run_output(o.out, tmp / "data/../data/", o.inputs, o.nerf).state, StageOutput::State::kComplete);

  auto stale_because = [&](const std::string& dataset, const TrainInputs& inputs, const NerfOptions& options) {
    const StageOutput s = nerf_run_output(o.out, dataset, inputs, options);
    EXPECT_EQ(s.state, StageOutput::State::kStale) << s.why;
    return s.why;
  };
  // Every option: the table must name each key the record holds, so a new option is varied too.
  const Json recorded = read_json_file(o.out + "/run.json").at("options");
  const auto changes = one_change_per_key();
  for (const auto& [key, value] : recorded.items()) EXPECT_TRUE(changes.count(key)) << "vary " << key << " too";
  for (const auto& [key, change] : changes) {
    SCOPED_TRACE(key);
    NerfOptions other = o.nerf;
    change(other);
    other.validate("test");
    const std::string why = stale_because(o.dataset, o.inputs, other);
    EXPECT_EQ(why.rfind("options.", 0), 0u) << why;  // the first differing key (keys in JSON order)
    EXPECT_TRUE(why.find(key) != std::string::npos || (key == "upsample_at" && why.find("level_scales") != std::string::npos))
        << why;
  }
  // The data: another dataset folder, other images, masks or points.
  copy_tree(tmp / "data", tmp / "copy");
  EXPECT_EQ(stale_because(tmp / "copy", o.inputs, o.nerf).rfind("dataset: ", 0), 0u);
  TrainInputs clean = o.inputs;
  clean.images = TrainImages::kClean;
  EXPECT_EQ(stale_because(o.dataset, clean, o.nerf).rfind("images: ", 0), 0u);
  TrainInputs masked = o.inputs;
  masked.masks_dir = tmp / "masks";
  EXPECT_EQ(stale_because(o.dataset, masked, o.nerf).rfind("masks_dir: ", 0), 0u);
  TrainInputs points = o.inputs;
  points.points_dir = tmp / "points";
  EXPECT_EQ(stale_because(o.dataset, points, o.nerf).rfind("points_dir: ", 0), 0u);

  // An incomplete run is judged by the same rule: stale with other settings, absent with these.
  Json j = read_json_file(o.out + "/run.json");
  j["complete"] = false;
  write_file_atomic(o.out + "/run.json", j.dump());
  EXPECT_EQ(nerf_run_output(o.out, o.dataset, o.inputs, o.nerf).state, StageOutput::State::kAbsent);
  NerfOptions seed = o.nerf;
  seed.seed = 5;
  EXPECT_EQ(stale_because(o.dataset, o.inputs, seed), "options.seed: holds 4, asked for 5");
}


// Stands in for a kill: thrown from the progress callback after the step of `at`.
struct Stopped {};
NerfIterationCallback stop_at(int at) {
  return [at](const NerfIterationStats& st) {
    if (st.iteration == at) throw Stopped{};
  };
}

TEST(NerfRunTest, AStoppedRunResumesFromItsCheckpointToTheSameField) {
  weathergs::testing::TempDir tmp;
  NerfRunOptions o = tiny_run(tmp);
  o.nerf.iterations = 9;
  o.nerf.level_scales = {0.5, 1.0};
  o.nerf.upsample_at = {4};
  o.checkpoint_every = 3;
  o.snapshot_at = {5};
  o.out = tmp / "straight";
  train_nerf_run(o);
  EXPECT_FALSE(fs::exists(o.out + "/checkpoint.bin")) << "a complete run keeps no checkpoint";
  const std::string straight = read_file(o.out + "/field.bin");

  o.out = tmp / "stopped";
  // Stopped after 5: the checkpoint of 3 is on the coarse level, so the resumed run makes the scale-up.
  EXPECT_THROW(train_nerf_run(o, stop_at(5)), Stopped);
  const StageOutput partial = nerf_run_output(o.out, o.dataset, o.inputs, o.nerf);
  EXPECT_EQ(partial.state, StageOutput::State::kPartial) << partial.why;
  EXPECT_FALSE(read_json_file(o.out + "/run.json").at("complete").get<bool>());
  EXPECT_EQ(read_json_file(o.out + "/run.json").at("iterations").get<int>(), 3);
  // Starting over needs force; resuming with other options is refused, naming the option.
  EXPECT_THROW(train_nerf_run(o), InputError);
  NerfRunOptions other = o;
  other.resume = true;
  other.nerf.seed = 5;
  try {
    train_nerf_run(other);
    ADD_FAILURE() << "resumed a run of another seed";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("options.seed"), std::string::npos) << e.what();
  }
  o.resume = true;
  EXPECT_THROW(train_nerf_run(o, stop_at(8)), Stopped);  // from 3 on, and stopped again past the checkpoint of 6
  EXPECT_EQ(read_json_file(o.out + "/run.json").at("iterations").get<int>(), 6);
  const NerfRunResult resumed = train_nerf_run(o);
  EXPECT_EQ(resumed.iterations, 9);
  EXPECT_TRUE(read_file(o.out + "/field.bin") == straight) << "the resumed field differs from the uninterrupted one";
  EXPECT_FALSE(fs::exists(o.out + "/checkpoint.bin"));
  EXPECT_TRUE(fs::exists(nerf_snapshot_dir(o.out, 5) + "/info.json"));
  ASSERT_TRUE(resumed.train_cpu_seconds.has_value());
  EXPECT_GT(*resumed.train_cpu_seconds, 0);
  EXPECT_EQ(nerf_run_output(o.out, o.dataset, o.inputs, o.nerf).state, StageOutput::State::kComplete);
  EXPECT_THROW(train_nerf_run(o), InputError) << "a complete run has nothing to resume";

  // A damaged checkpoint is an error naming the file, not a silently different field.
  o.resume = false, o.force = true;
  EXPECT_THROW(train_nerf_run(o, stop_at(4)), Stopped);
  const std::string ckpt = o.out + "/checkpoint.bin";
  const std::string bytes = read_file(ckpt);
  write_file_atomic(ckpt, bytes.substr(0, bytes.size() - 4));
  o.resume = true, o.force = false;
  try {
    train_nerf_run(o);
    ADD_FAILURE() << "resumed from a truncated checkpoint";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("checkpoint.bin"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace weathergs::nerf
