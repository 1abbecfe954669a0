// End to end through the `weathergs` binary: train, checkpoint/resume, render, errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "core/atomic_file.h"
#include "core/json_reader.h"
#include "reconstruction/gaussians.h"
#include "reconstruction/trainer.h"
#include "tests/core/test_util.h"
#include "tests/reconstruction/test_scene.h"

namespace weathergs::reconstruction {
namespace {

namespace fs = std::filesystem;

int run(const std::string& args) {
  const std::string cmd = std::string(WEATHERGS_BINARY) + " --quiet " + args + " > /dev/null 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(CliTest, TrainResumeRender) {
  weathergs::testing::TempDir dir;
  const GaussianSet<float> truth = testing::random_gaussians<float>(120, 4, 1.0, 0.12, 0.0);
  const Dataset d = testing::write_synthetic_dataset(dir / "data", truth, testing::ring_cameras(9, 48, 32, 44, 4.0), true);
  const std::string data = dir / "data", runp = dir / "run";
  ASSERT_EQ(run("train --data " + data + " --iterations 40 --checkpoint-every 20 --out " + runp), 0);
  for (const char* f : {"run.json", "point_cloud.ply", "checkpoint.bin"}) EXPECT_TRUE(fs::exists(fs::path(runp) / f)) << f;
  JsonReader info = JsonReader::from_file(runp + "/run.json");
  EXPECT_TRUE(info.get<bool>("complete"));
  EXPECT_EQ(info.get<int>("iterations"), 40);
  EXPECT_EQ(info.get<std::string>("initialization"), "colmap:120");
  // The large-Gaussian prune's start, scaled with the run: 3000 x 40 / 30000.
  EXPECT_EQ(info.child("effective_schedule").get<int>("large_prune_from"), 4);
  const std::string ply40 = read_file(runp + "/point_cloud.ply");
  // An existing run is not overwritten by accident.
  EXPECT_EQ(run("train --data " + data + " --iterations 40 --out " + runp), 2);
  // Resuming with a changed option is refused; --force starts over and reproduces the same model.
  EXPECT_EQ(run("train --resume --iterations 40 --seed 5 --out " + runp), 2);
  EXPECT_EQ(run("train --resume --large-prune-from 7 --out " + runp), 2);
  EXPECT_EQ(run("train --data " + data + " --large-prune-from -1 --out " + dir / "r1"), 2);
  ASSERT_EQ(run("train --data " + data + " --iterations 40 --checkpoint-every 20 --force --out " + runp), 0);
  EXPECT_EQ(read_file(runp + "/point_cloud.ply"), ply40);
  // Resume of a finished run is a no-op that keeps the model.
  ASSERT_EQ(run("train --resume --out " + runp), 0);
  EXPECT_EQ(read_file(runp + "/point_cloud.ply"), ply40);

  const std::string renders = dir / "renders";
  ASSERT_EQ(run("render --model " + runp + " --split test --out " + renders), 0);
  for (const std::string& v : d.split("test")) {
    const Image img = read_image(renders + "/" + v + ".png");
    EXPECT_EQ(img.width, 48);
    EXPECT_EQ(img.height, 32);
  }
  JsonReader ri = JsonReader::from_file(renders + "/info.json");
  EXPECT_EQ(ri.get<std::string>("method"), "3dgs");
  EXPECT_EQ(ri.get<int>("iterations"), 40);
  EXPECT_GT(ri.get<int64_t>("num_gaussians"), 0);
  EXPECT_GT(ri.get<double>("peak_rss_mb"), 0);
  EXPECT_GE(ri.get<double>("train_seconds"), 0);
  // The training's CPU seconds (every thread's), carried from run.json: there, and not more than
  // its wall seconds times the cores its threads may use, with a scheduler tick's slack.
  const JsonReader now = JsonReader::from_file(runp + "/run.json");
  const double cpu = ri.get<double>("train_cpu_seconds");
  EXPECT_GT(cpu, 0);
  EXPECT_LE(cpu, std::max(1u, std::thread::hardware_concurrency()) * now.get<double>("train_seconds") + 0.02);
  EXPECT_EQ(cpu, now.get<double>("train_cpu_seconds"));
  EXPECT_GE(ri.get<double>("render_seconds"), 0);
  ri.finish();
  EXPECT_EQ(weathergs::testing::count_entries(renders), int(d.split("test").size()) + 1);

  // Bad input: exit code 2 and nothing written.
  EXPECT_EQ(run("train --data " + dir / "missing" + " --out " + dir / "r2"), 2);
  EXPECT_EQ(run("train --data " + data + " --masks lens --out " + dir / "r3"), 2);  // no masks/lens
  EXPECT_EQ(run("render --model " + dir / "missing" + " --out " + dir / "r4"), 2);
  EXPECT_FALSE(fs::exists(dir / "r4"));
  EXPECT_EQ(run("render --model " + runp + " --split nope --out " + dir / "r5"), 2);
  EXPECT_FALSE(fs::exists(dir / "r5"));
}

TEST(CliTest, TrainOptionsFileUnderTheGivenFlags) {
  weathergs::testing::TempDir dir;
  const GaussianSet<float> truth = testing::random_gaussians<float>(60, 2, 1.0, 0.12, 0.0);
  testing::write_synthetic_dataset(dir / "data", truth, testing::ring_cameras(6, 32, 24, 30, 4.0), true);
  const std::string data = dir / "data", file = dir / "options.json";
  write_file_atomic(file, R"({"iterations": 30, "densify_until": 20, "lambda_dssim": 0.5, "max_gaussians": 5000})");
  // The file's keys, a flag given on the command line over it, the rest at their defaults.
  ASSERT_EQ(run("train --data " + data + " --train-options " + file + " --iterations 24 --out " + dir / "run"), 0);
  const JsonReader o = JsonReader::from_file(dir / "run" + "/run.json").child("options");
  EXPECT_EQ(o.get<int>("iterations"), 24);
  EXPECT_EQ(o.get<int>("densify_until"), 20);
  EXPECT_DOUBLE_EQ(o.get<double>("lambda_dssim"), 0.5);
  EXPECT_EQ(o.get<int64_t>("max_gaussians"), 5000);
  EXPECT_EQ(o.get<int>("densify_from"), TrainOptions{}.densify_from);
  // Including the keys whose absence from a run record means the rule older runs trained with.
  EXPECT_EQ(o.get<std::string>("large_prune"), to_string(TrainOptions{}.large_prune));
  EXPECT_EQ(o.get<int>("large_prune_from"), TrainOptions{}.large_prune_from);
  // A misspelled key or a bad value is an error before training.
  write_file_atomic(file, R"({"densify_untill": 20})");
  EXPECT_EQ(run("train --data " + data + " --train-options " + file + " --out " + dir / "r2"), 2);
  write_file_atomic(file, R"({"iterations": -1})");
  EXPECT_EQ(run("train --data " + data + " --train-options " + file + " --out " + dir / "r3"), 2);
  // A key the run would never read: the dataset has SfM points, so no random initialization runs.
  write_file_atomic(file, R"({"random_init": "frustum"})");
  EXPECT_EQ(run("train --data " + data + " --train-options " + file + " --out " + dir / "r4"), 2);
  EXPECT_FALSE(fs::exists(dir / "r2"));
  EXPECT_FALSE(fs::exists(dir / "r4"));
}

TEST(CliTest, MaskAndImageFolders) {
  weathergs::testing::TempDir dir;
  const GaussianSet<float> truth = testing::random_gaussians<float>(60, 5, 1.0, 0.12, 0.0);
  const Dataset d = testing::write_synthetic_dataset(dir / "data", truth, testing::ring_cameras(9, 40, 30, 36, 4.0), true);
  // A mask folder (255 = ignore) covering part of every train view, and a copy of the images as a
  // custom image folder.
  fs::create_directories(dir / "masks");
  fs::create_directories(dir / "imgs");
  for (const std::string& v : d.split("train")) {
    Image m(40, 30, 1, ColorSpace::kLinear);
    for (int y = 0; y < 10; ++y)
      for (int x = 0; x < 15; ++x) m.at(x, y) = 1.f;
    write_mask(dir / "masks/" + v + ".png", m);
    fs::copy_file(d.path(ImageKind::kImages, v), dir / "imgs/" + v + ".png");
  }
  ASSERT_EQ(run("train --data " + dir / "data" + " --images-dir " + dir / "imgs" + " --masks-dir " + dir / "masks" +
                " --iterations 10 --out " + dir / "run"),
            0);
  JsonReader info = JsonReader::from_file(dir / "run/run.json");
  EXPECT_EQ(info.get<std::string>("masks_dir"), dir / "masks");
  EXPECT_EQ(info.get<std::string>("images_dir"), dir / "imgs");
  EXPECT_EQ(info.get<std::string>("masks"), "none");
  EXPECT_EQ(info.child("options").get<std::string>("mask_normalization"), "valid");
  // The WeatherGS release's normalisation is recorded, kept on --resume, and a model differs from
  // the default's (the masked loss is not the same loss).
  ASSERT_EQ(run("train --data " + dir / "data" + " --masks-dir " + dir / "masks" +
                " --mask-normalization reference --iterations 10 --checkpoint-every 5 --out " + dir / "ref"),
            0);
  EXPECT_EQ(JsonReader::from_file(dir / "ref/run.json").child("options").get<std::string>("mask_normalization"),
            "reference");
  ASSERT_EQ(run("train --data " + dir / "data" + " --masks-dir " + dir / "masks" + " --iterations 10 --out " + dir / "val"),
            0);
  EXPECT_NE(read_file(dir / "ref/point_cloud.ply"), read_file(dir / "val/point_cloud.ply"));
  const std::string ref_ply = read_file(dir / "ref/point_cloud.ply");
  ASSERT_EQ(run("train --resume --out " + dir / "ref"), 0);  // the stored normalisation: a no-op
  EXPECT_EQ(read_file(dir / "ref/point_cloud.ply"), ref_ply);
  EXPECT_EQ(run("train --resume --mask-normalization valid --out " + dir / "ref"), 2);  // a changed option
  EXPECT_EQ(run("train --data " + dir / "data" + " --mask-normalization half --out " + dir / "r1"), 2);
  // A folder is never mistaken for a mode, nor a mode for a folder (a folder named "lens" is a folder).
  EXPECT_EQ(run("train --data " + dir / "data" + " --masks " + dir / "masks" + " --out " + dir / "r1"), 2);
  EXPECT_EQ(run("train --data " + dir / "data" + " --masks lens --masks-dir " + dir / "masks" + " --out " + dir / "r1"),
            2);
  EXPECT_FALSE(fs::exists(dir / "r1"));
  // Missing folders and wrongly sized masks are input errors.
  EXPECT_EQ(run("train --data " + dir / "data" + " --images clean --out " + dir / "r2"), 2);
  write_mask(dir / "masks/" + d.split("train")[0] + ".png", Image(8, 8, 1, ColorSpace::kLinear));
  EXPECT_EQ(run("train --data " + dir / "data" + " --masks-dir " + dir / "masks" + " --out " + dir / "r3"), 2);
  EXPECT_FALSE(fs::exists(dir / "r2"));
  EXPECT_FALSE(fs::exists(dir / "r3"));
}

// --schedule reference at a shorter --iterations is the protocol's schedule scaled to it
// (docs/schedules.md): the same model, byte for byte, as --schedule unscaled with those counts typed
// in by hand. Unscaled with the protocol's own counts (no densification before 500) is another model.
TEST(CliTest, ReferenceScheduleIsTheUnscaledOneWithTheCountsScaledByHand) {
  weathergs::testing::TempDir dir;
  const GaussianSet<float> truth = testing::random_gaussians<float>(80, 6, 1.0, 0.12, 0.0);
  testing::write_synthetic_dataset(dir / "data", truth, testing::ring_cameras(6, 32, 24, 30, 4.0), true);
  const std::string data = dir / "data", file = dir / "scaled.json";
  ASSERT_EQ(run("train --data " + data + " --schedule reference --iterations 300 --out " + dir / "reference"), 0);
  // s = 300 / 30000: densify 5..150, every 18 (145 / 8 steps: the floor of 8), resets 30 steps apart,
  // the SH degree every 10, the large-Gaussian prune from 30.
  write_file_atomic(file, R"({"densify_from": 5, "densify_until": 150, "densification_interval": 18,
      "opacity_reset_interval": 540, "sh_degree_interval": 10, "large_prune_from": 30})");
  ASSERT_EQ(run("train --data " + data + " --schedule unscaled --iterations 300 --train-options " + file + " --out " +
                dir / "hand"),
            0);
  ASSERT_EQ(run("train --data " + data + " --schedule unscaled --iterations 300 --out " + dir / "unscaled"), 0);
  const std::string reference = read_file(dir / "reference/point_cloud.ply");
  EXPECT_EQ(reference, read_file(dir / "hand/point_cloud.ply"));
  EXPECT_EQ(read_json_file(dir / "reference/run.json").at("effective_schedule"),
            read_json_file(dir / "hand/run.json").at("effective_schedule"));
  EXPECT_NE(reference, read_file(dir / "unscaled/point_cloud.ply"));
}

// The resolution schedule through the binary: recorded in run.json, and it changes the model; its
// share of the run without a start factor cannot take effect and is refused.
TEST(CliTest, DownsampleStartThroughTheBinary) {
  weathergs::testing::TempDir dir;
  const GaussianSet<float> truth = testing::random_gaussians<float>(80, 7, 1.0, 0.12, 0.0);
  testing::write_synthetic_dataset(dir / "data", truth, testing::ring_cameras(6, 32, 24, 30, 4.0), true);
  const std::string data = dir / "data";
  ASSERT_EQ(run("train --data " + data + " --iterations 40 --downsample-start 4 --full-resolution-at 0.8 --out " +
                dir / "low"),
            0);
  const Json options = read_json_file(dir / "low/run.json").at("options");
  EXPECT_EQ(options.at("downsample_start"), 4);
  EXPECT_EQ(options.at("full_resolution_at"), 0.8);
  ASSERT_EQ(run("train --data " + data + " --iterations 40 --out " + dir / "full"), 0);
  EXPECT_EQ(read_json_file(dir / "full/run.json").at("options").at("downsample_start"), 1);
  EXPECT_NE(read_file(dir / "low/point_cloud.ply"), read_file(dir / "full/point_cloud.ply"));
  EXPECT_EQ(run("train --data " + data + " --iterations 40 --full-resolution-at 0.8 --out " + dir / "bad"), 2);
  EXPECT_EQ(run("train --data " + data + " --iterations 40 --downsample-start 3 --out " + dir / "bad"), 2);
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

}  // namespace
}  // namespace weathergs::reconstruction
