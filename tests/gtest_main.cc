// One test main for every test binary (COLMAP's gtest_main): fixes the thread count from the
// environment (WEATHERGS_TEST_THREADS, default: all cores) so determinism tests can force it, and
// makes progress output quiet. Exit codes for ctest: 0 every test passed, 1 any failed (whatever else
// was skipped), 77 none failed and at least one skipped (GTEST_SKIP: a missing tool), so that a
// failure is never reported as a skip.
#include <gtest/gtest.h>

#include <cstdlib>

#include "core/parallel.h"
#include "core/progress.h"

namespace {
constexpr int kSkipExitCode = 77;  // ctest's SKIP_RETURN_CODE (cmake/WeatherGS.cmake)
}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  weathergs::set_quiet(true);
  const char* t = std::getenv("WEATHERGS_TEST_THREADS");
  weathergs::set_num_threads(t ? std::atoi(t) : 0);
  if (RUN_ALL_TESTS() != 0) return 1;
  return ::testing::UnitTest::GetInstance()->skipped_test_count() > 0 ? kSkipExitCode : 0;
}
