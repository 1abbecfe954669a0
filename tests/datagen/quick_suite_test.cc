// The quick suite through the CLI, from an empty cache: six complete datasets whose COLMAP exports
// are readable and accurate. Labelled slow; the time budget (one variant < 3 min, the suite
// < 15 min on 2 idle cores) is measured and recorded in benchmarks/README.md, and printed here.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "datagen/colmap.h"
#include "datagen/process.h"
#include "tests/core/test_util.h"

namespace weathergs::datagen {
namespace {

using testing::TempDir;
constexpr double kMaxReprojectionErrorPx = 1.0;  // the bar

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
      EXPECT_EQ(v[model]["registered_images"], 16) << ds.info.name;
      EXPECT_GT(v[model]["points"].get<int>(), 200) << ds.info.name;
      EXPECT_LT(v[model]["mean_reprojection_error_px"].get<double>(), kMaxReprojectionErrorPx) << ds.info.name;
    }
  }
}

}  // namespace
}  // namespace weathergs::datagen
