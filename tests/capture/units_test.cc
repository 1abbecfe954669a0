// Pieces of capture that need no Blender or COLMAP: the process runner and transforms.json.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"
#include "capture/exports.h"
#include "capture/process.h"
#include "tests/core/test_util.h"

namespace weathergs::capture {
namespace {

using testing::TempDir;

TEST(ProcessTest, ExitCodesOutputAndLogs) {
  TempDir tmp;
  ProcessOptions o;
  o.log_path = tmp / "log.txt";
  o.stdout_path = tmp / "out.txt";
  ProcessResult r = run_process({"sh", "-c", "echo hello; echo oops >&2; exit 3"}, "sh", o);
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_EQ(read_file(tmp / "out.txt"), "hello\n");
  EXPECT_EQ(read_file(tmp / "log.txt"), "oops\n");
  EXPECT_NE(tail_of_file(tmp / "log.txt").find("| oops"), std::string::npos);
  // Arguments are passed verbatim, no shell: quotes and spaces survive.
  o.log_path = tmp / "log2.txt";
  r = run_process({"printf", "%s|", "a b", "'c'"}, "printf", o);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(read_file(tmp / "out.txt"), "a b|'c'|");
}

// An entry of ProcessOptions::env replaces the parent's variable of that name (getenv in the child
// returns the first match, so appending it after the parent's would not take effect).
TEST(ProcessTest, EnvironmentEntriesReplaceTheParents) {
  TempDir tmp;
  ASSERT_EQ(::setenv("WEATHERGS_PROCESS_TEST_VAR", "parent", 1), 0);
  ProcessOptions o;
  o.stdout_path = tmp / "out.txt";
  EXPECT_EQ(run_process({"printenv", "WEATHERGS_PROCESS_TEST_VAR"}, "printenv", o).exit_code, 0);
  EXPECT_EQ(read_file(tmp / "out.txt"), "parent\n");
  o.env = {"WEATHERGS_PROCESS_TEST_VAR=child", "WEATHERGS_PROCESS_TEST_NEW=x=y"};
  EXPECT_EQ(run_process({"printenv", "WEATHERGS_PROCESS_TEST_VAR"}, "printenv", o).exit_code, 0);
  EXPECT_EQ(read_file(tmp / "out.txt"), "child\n");
  EXPECT_EQ(run_process({"printenv", "WEATHERGS_PROCESS_TEST_NEW"}, "printenv", o).exit_code, 0);
  EXPECT_EQ(read_file(tmp / "out.txt"), "x=y\n");
  ::unsetenv("WEATHERGS_PROCESS_TEST_VAR");
}

TEST(ProcessTest, MissingExecutableAndTimeout) {
  try {
    run_process({"weathergs-no-such-tool"}, "tool");
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not found on PATH"), std::string::npos) << e.what();
  }
  EXPECT_EQ(find_executable("weathergs-no-such-tool"), "");
  EXPECT_NE(find_executable("sh"), "");
  ProcessOptions o;
  o.timeout_s = 0.3;
  const auto start = std::chrono::steady_clock::now();
  EXPECT_THROW(run_process({"sleep", "30"}, "sleep", o), InputError);
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
}

TEST(ExportsTest, TransformsJsonUsesOpenGlAxes) {
  Camera c;
  c.name = "007";
  c.width = 600, c.height = 400;
  c.fx = c.fy = 500, c.cx = 300, c.cy = 200;
  // Camera at (1, 2, 3) looking along world +y, image x = world +x, image y = world -z.
  Eigen::Matrix3d r;
  r << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  c.camera_from_world.topLeftCorner<3, 3>() = r;
  c.camera_from_world.topRightCorner<3, 1>() = -r * Eigen::Vector3d(1, 2, 3);
  const Json j = transforms_json({c});
  ASSERT_EQ(j["frames"].size(), 1u);
  const Json& m = j["frames"][0]["transform_matrix"];
  // OpenGL camera: x right (+x world), y up (+z world), z backward (-y world); translation = center.
  const double expected[3][4] = {{1, 0, 0, 1}, {0, 0, -1, 2}, {0, 1, 0, 3}};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 4; ++k) EXPECT_NEAR(m[i][k].get<double>(), expected[i][k], 1e-12) << i << "," << k;
  EXPECT_EQ(j["frames"][0]["file_path"], "images/007.png");
  EXPECT_EQ(j["fl_x"], 500.0);
  EXPECT_EQ(j["w"], 600);
}

}  // namespace
}  // namespace weathergs::capture
