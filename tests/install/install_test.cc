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
  // Every file of the repository's models/ reaches share/, byte for byte: the LPIPS weights, their
  // licence and manifest, and the project's own AEF and LED weights.
  const fs::path models = fs::path(WEATHERGS_SOURCE_DIR) / "models";
  int files = 0;
  for (const auto& e : fs::recursive_directory_iterator(models)) {
    if (!e.is_regular_file() || e.path().parent_path() == models) continue;  // models/README.md is documentation
    const fs::path rel = fs::relative(e.path(), models);
    const fs::path installed = fs::path(prefix) / "share/weathergs/models" / rel;
    ASSERT_TRUE(fs::exists(installed)) << rel;
    EXPECT_EQ(read_file(installed.string()), read_file(e.path().string())) << rel;
    ++files;
  }
  EXPECT_GE(files, 12) << "models/lpips (onnx, NOTICE, manifest, references), models/led, models/aef";

  // Run from a directory that has nothing of the project near it.
  const std::string elsewhere = tmp / "elsewhere";
  fs::create_directories(elsewhere);
  const std::string a = std::string(WEATHERGS_TEST_DATA_DIR) + "/ssim/blur_a.png";
  const std::string b = std::string(WEATHERGS_TEST_DATA_DIR) + "/ssim/blur_b.png";
  // LPIPS is scored with the installed weights, from a folder with nothing of the project near it.
  EXPECT_EQ(run_in(elsewhere, bin + " compare " + a + " " + b, tmp / "compare.log", &out), 0) << out;
  EXPECT_NE(out.find("LPIPS"), std::string::npos) << out;
  EXPECT_EQ(out.find("LPIPS skipped"), std::string::npos) << out;
  // Without them, the error says where it looked and how to provide them.
  fs::rename(fs::path(prefix) / "share/weathergs/models/lpips", tmp / "lpips_moved");
  EXPECT_EQ(run_in(elsewhere, bin + " compare " + a + " " + b, tmp / "compare2.log", &out), 2) << out;
  EXPECT_NE(out.find("share/weathergs/models/lpips"), std::string::npos) << out;
  EXPECT_NE(out.find("--lpips-model"), std::string::npos) << out;
  fs::rename(tmp / "lpips_moved", fs::path(prefix) / "share/weathergs/models/lpips");
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
