// A probe of the test main's exit codes (tests/gtest_main.cc), run by skip_convention_test.sh: with
// WEATHERGS_SKIP_PROBE=skip one TEST skips; =skip_and_fail one skips and one fails.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace {

std::string probe() {
  const char* p = std::getenv("WEATHERGS_SKIP_PROBE");
  return p ? p : "";
}

TEST(SkipProbe, Skips) {
  if (!probe().empty()) GTEST_SKIP() << "probe: a missing tool";
}

TEST(SkipProbe, FailsWhenAsked) { EXPECT_NE(probe(), "skip_and_fail") << "probe: a real failure beside a skip"; }

}  // namespace
