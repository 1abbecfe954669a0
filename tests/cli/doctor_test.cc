// `weathergs doctor`: every resource of a built tree is found; a missing one is named with how to
// provide it (exit 1 in the listing, exit 2 with --need, before any work).
#include <gtest/gtest.h>

#include "tests/core/test_util.h"

namespace weathergs {
namespace {

using testing::run_command;

const std::string kBin = WEATHERGS_BINARY;

TEST(Doctor, ABuiltTreeHasEverythingAndAMissingResourceIsNamed) {
  auto r = run_command(kBin + " doctor");
  // Blender and COLMAP are installed by `make test`; the weights and scripts are staged by the build.
  EXPECT_EQ(r.exit_code, 0) << r.output;
  for (const char* name : {"lpips", "led", "aef", "blender-script"}) EXPECT_NE(r.output.find(name), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("MISSING"), std::string::npos) << r.output;

  r = run_command("env WEATHERGS_LPIPS_MODEL=/nonexistent/lpips " + kBin + " doctor");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("MISSING  lpips"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--lpips-model"), std::string::npos) << r.output;

  r = run_command(kBin + " doctor --need blender --blender /nonexistent/blender");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("Blender not found"), std::string::npos) << r.output;

  r = run_command(kBin + " doctor --need out --out /dev/null/run");
  EXPECT_EQ(r.exit_code, 2) << r.output;

  r = run_command(kBin + " doctor --need wings");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("unknown resource 'wings'"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace weathergs
