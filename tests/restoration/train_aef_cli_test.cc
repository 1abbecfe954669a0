// `weathergs train-aef` through the binary, as a user runs it: a tiny training on a generated rainy
// dataset lowers its loss and writes a loadable plugin; bad inputs exit 2 and leave nothing.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "core/json_reader.h"
#include "restoration/aef/aef_plugin.h"
#include "tests/core/test_util.h"
#include "tests/restoration/restoration_test_util.h"

namespace weathergs::restoration::aef {
namespace {

namespace fs = std::filesystem;
using testing_util::run_cli;
using weathergs::testing::TempDir;

// Four views of the synthetic wall in heavy rain, with the targets and masks train-aef reads.
std::string rainy_dataset(const TempDir& tmp) {
  weathergs::testing::SceneOptions so;
  so.views = 4;
  so.width = 128;
  so.height = 96;
  weathergs::testing::make_clean_dataset(tmp / "clean", so);
  write_file_atomic(tmp / "spec.json", R"({"seed": 5, "style": "paper", "effects": {"rain": {"intensity": "heavy"}}})");
  const std::string out = tmp / "rain";
  EXPECT_EQ(run_cli("weather --in " + (tmp / "clean") + " --spec " + (tmp / "spec.json") + " --out " + out + " --targets",
                    tmp / "w.log"),
            0)
      << read_file(tmp / "w.log");
  return out;
}

// How much a 600-iteration training must lower its loss: to at most this fraction of the first 50
// iterations' mean (measured 0.70; a broken gradient or data path leaves it near 1).
constexpr double kMinLossRatio = 0.9;

TEST(TrainAefCli, ATinyTrainingLowersItsLossAndWritesALoadablePlugin) {
  TempDir tmp;
  const std::string data = rainy_dataset(tmp);
  auto train = [&](const std::string& stem) {
    return run_cli("--threads 1 train-aef --model derain --data " + data + " --out " + stem +
                       " --iterations 600 --batch 4 --crop 32 --channels 4 --learning-rate 0.005",
                   stem + ".log");
  };
  const std::string stem = tmp / "derain";
  ASSERT_EQ(train(stem), 0) << read_file(stem + ".log");
  const Json m = read_json_file(stem + ".json");
  const std::vector<double> curve = m.at("training").at("loss_per_50_iterations").get<std::vector<double>>();
  ASSERT_EQ(curve.size(), 12u);
  std::string shown;
  for (double c : curve) shown += " " + std::to_string(c);
  std::printf("train-aef loss per 50 iterations:%s\n", shown.c_str());
  // The batches differ, so the curve is noisy: the mean of the last two windows against the first.
  EXPECT_LT((curve[10] + curve[11]) / 2, kMinLossRatio * curve[0]) << shown;
  const AefPlugin p = AefPlugin::load(stem, AefPluginKind::kDerain);
  EXPECT_GT(p.parameter_count(), 0);
  // The same command gives the same weights (one thread, fixed seed).
  ASSERT_EQ(train(tmp / "again"), 0) << read_file(tmp / "again.log");
  EXPECT_EQ(read_file(stem + ".bin"), read_file(tmp / "again.bin"));
}

TEST(TrainAefCli, BadInputsExitTwoAndLeaveNothing) {
  TempDir tmp;
  const std::string data = rainy_dataset(tmp);
  fs::create_directories(tmp / "no_targets");
  for (const char* f : {"dataset.json", "cameras.json"}) fs::copy_file(data + "/" + f, tmp / ("no_targets/" + std::string(f)));
  copy_tree(data + "/images", tmp / "no_targets/images");
  struct Case {
    std::string args, expect;
  };
  const std::vector<Case> cases = {
      {"--model derain --data " + (tmp / "none"), "none"},
      {"--model dehaze --data " + data, "dehaze"},
      {"--model derain --data " + data + " --held-out " + data, "held"},
      {"--model derain --data " + data + " --iterations -5", "iterations"},
      {"--model derain --data " + data + " --crop 4", "crop"},
      {"--model derain --data " + (tmp / "no_targets"), "targets"},  // a weathered dataset without them
  };
  int i = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args);
    const std::string stem = tmp / ("w" + std::to_string(i++));
    EXPECT_EQ(run_cli("train-aef " + c.args + " --out " + stem, tmp / "bad.log"), 2) << read_file(tmp / "bad.log");
    EXPECT_NE(read_file(tmp / "bad.log").find(c.expect), std::string::npos) << read_file(tmp / "bad.log");
    EXPECT_FALSE(fs::exists(stem + ".json") || fs::exists(stem + ".bin"));
  }
}

}  // namespace
}  // namespace weathergs::restoration::aef
