// The installed binary finds its data (LPIPS weights, Blender script, scenes) through the install
// prefix, from any working directory, and carries no source-tree path (docs/architecture.md).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/atomic_file.h"
#include "tests/core/test_util.h"

namespace weathergs {
namespace {

namespace fs = std::filesystem;

// Runs a shell command from `cwd`; returns its exit code, output in *out.
int run_in(const std::string& cwd, const std::string& cmd, const std::string& log, std::string* out) {
  const std::string full = "cd '" + cwd + "' && env -u WEATHERGS_LPIPS_MODEL -u WEATHERGS_BLENDER_SCRIPT " + cmd +
                           " > '" + log + "' 2>&1";
  const int status = std::system(full.c_str());
  *out = read_file(log);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(InstallTest, InstalledBinaryFindsItsDataFromAnyDirectory) {
  testing::TempDir tmp;
  const std::string prefix = tmp / "prefix";
  std::string out;
  ASSERT_EQ(run_in(tmp.path(), "cmake --install '" + std::string(WEATHERGS_BUILD_DIR) + "' --prefix '" + prefix + "'",
                   tmp / "install.log", &out),
            0)
      << out;
  const std::string bin = prefix + "/bin/weathergs";
  ASSERT_TRUE(fs::exists(bin));
  for (const char* f : {"share/weathergs/blender_scripts/render_scene.py", "share/weathergs/scenes/pool.json",
                        "share/doc/weathergs/architecture.md"})
    EXPECT_TRUE(fs::exists(fs::path(prefix) / f)) << f;

  // Run from a directory that has nothing of the project near it.
  const std::string elsewhere = tmp / "elsewhere";
  fs::create_directories(elsewhere);
  const std::string a = std::string(WEATHERGS_TEST_DATA_DIR) + "/ssim/blur_a.png";
  const std::string b = std::string(WEATHERGS_TEST_DATA_DIR) + "/ssim/blur_b.png";
  if (fs::exists(fs::path(prefix) / "share/weathergs/models/lpips/lpips_alex_v0.1.onnx")) {
    EXPECT_EQ(run_in(elsewhere, bin + " compare " + a + " " + b, tmp / "compare.log", &out), 0) << out;
    EXPECT_NE(out.find("LPIPS"), std::string::npos) << out;
  } else {
    // Configured without the weights: the error says where it looked and how to fix it.
    EXPECT_EQ(run_in(elsewhere, bin + " compare " + a + " " + b, tmp / "compare.log", &out), 2) << out;
    EXPECT_NE(out.find("share/weathergs/models/lpips"), std::string::npos) << out;
  }
  // The Blender script is found in the prefix: with a "Blender" that fails, generate gets as far as
  // running it (and reports its failure, exit 2), instead of failing to find render_scene.py.
  EXPECT_EQ(run_in(elsewhere,
                   bin + " --quiet generate --scene " + prefix + "/share/weathergs/scenes/pool.json --weather rain" +
                       " --profile tiny --no-colmap --blender /bin/false --cache " + (tmp / "cache") + " --out " +
                       (tmp / "out"),
                   tmp / "generate.log", &out),
            2)
      << out;
  EXPECT_EQ(out.find("render_scene.py not found"), std::string::npos) << out;
  EXPECT_NE(out.find("blender"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(tmp / "out"));
  // No source-tree path is compiled into the binary. (Not in a sanitizer build: the sanitizers'
  // source-location records keep full paths, which GCC 12's -ffile-prefix-map does not remap; an ASan
  // build of weathergs holds ~220 such strings.)
#ifndef WEATHERGS_SANITIZED
  EXPECT_EQ(read_file(bin).find(std::string(WEATHERGS_SOURCE_DIR) + "/"), std::string::npos);
#endif
}

}  // namespace
}  // namespace weathergs
