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

// The tools' versions are reported and held against those the benchmark's expected identities
// (scenes/expected/) were made with: another Blender is named before any generate refuses its data.
TEST(Doctor, ToolVersionsAreHeldAgainstTheBenchmarksIdentities) {
  if (run_command("command -v blender && command -v colmap").exit_code != 0) GTEST_SKIP() << "blender or colmap missing";
  auto r = run_command(kBin + " doctor --need blender,colmap,benchmark-tools");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("(3.4.1); the benchmark's identities were made with it"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("(COLMAP 3.8); the benchmark's identities were made with it"), std::string::npos) << r.output;
  testing::TempDir tmp;
  const std::string fake = tmp / "blender";
  ASSERT_EQ(run_command("printf '#!/bin/sh\\necho Blender 9.9.9\\n' > " + fake + " && chmod +x " + fake).exit_code, 0);
  r = run_command(kBin + " doctor --need benchmark-tools --blender " + fake);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("made with Blender 3.4.1, COLMAP 3.8, this machine has Blender 9.9.9, COLMAP 3.8"),
            std::string::npos)
      << r.output;
  r = run_command(kBin + " doctor --need blender --blender " + fake);
  EXPECT_EQ(r.exit_code, 0) << r.output;  // present, but its datasets will not match: said, not refused
  EXPECT_NE(r.output.find("(9.9.9); the benchmark's identities were made with 3.4.1"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace weathergs
