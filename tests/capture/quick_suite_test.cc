// The quick suite through the CLI, from an empty cache: six complete datasets whose COLMAP exports
// are readable and accurate. Labelled slow; the required time budget (one variant < 3 min, the suite
// < 15 min on 2 idle cores) is measured and recorded in benchmarks/README.md, and printed here.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "capture/colmap.h"
#include "capture/process.h"
#include "tests/core/test_util.h"

namespace weathergs::capture {
namespace {

using testing::TempDir;
constexpr double kMaxReprojectionErrorPx = 1.0;  // the required bar
// SfM points: the clean views give 520-1000 (data/suite_paper), so 200 says the scenes
// are textured enough to reconstruct. The weathered views carry the paper-style weather, which is
// meant to hurt (docs/scenes.md): their models keep 17-46% of the clean points (124-328 over two
// generations, tanabata_rain lowest) with every view registered, and 3DGS trains from such a cloud
// (pool_rain's ~190 points, docs/methods.md). Their floor of 100 catches a broken export or an SfM
// that lost the scene, not the weather doing its job.
constexpr int kMinCleanPoints = 200;
constexpr int kMinWeatheredPoints = 100;

TEST(QuickSuiteTest, SixVariantsFromScratch) {
  if (find_executable("blender").empty() || find_executable("colmap").empty()) GTEST_SKIP() << "tools missing";
  TempDir tmp;
  const std::string cmd = std::string(WEATHERGS_BINARY) + " --quiet generate --suite " + WEATHERGS_SOURCE_DIR +
                          "/scenes/suite.json --profile quick --cache " + (tmp / "cache") + " --out " +
                          (tmp / "suite") + " > " + (tmp / "log.txt") + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << read_file(tmp / "log.txt");
  std::printf("%s", read_file(tmp / "log.txt").c_str());
  const Json summary = read_json_file(tmp / "suite/summary.json");
  ASSERT_EQ(summary["variants"].size(), 6u);
  for (const auto& v : summary["variants"]) {
    const Dataset ds = read_dataset(v["out_dir"].get<std::string>());
    EXPECT_EQ(ds.cameras.size(), 16u);
    EXPECT_EQ(ds.cameras[0].width, 300);
    for (const char* model : {"sparse", "sparse_clean"}) {
      const int min_points = std::string(model) == "sparse" ? kMinWeatheredPoints : kMinCleanPoints;
      EXPECT_EQ(v[model]["registered_images"], 16) << ds.info.name;
      EXPECT_GT(v[model]["points"].get<int>(), min_points) << ds.info.name << " " << model;
      EXPECT_LT(v[model]["mean_reprojection_error_px"].get<double>(), kMaxReprojectionErrorPx) << ds.info.name;
    }
  }
}

}  // namespace
}  // namespace weathergs::capture
