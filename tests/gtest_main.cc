// One test main for every test binary (COLMAP's gtest_main): fixes the thread count from the
// environment (WEATHERGS_TEST_THREADS, default: all cores) so determinism tests can force it, and
// makes progress output quiet.
#include <gtest/gtest.h>

#include <cstdlib>

#include "core/parallel.h"
#include "core/progress.h"

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  weathergs::set_quiet(true);
  const char* t = std::getenv("WEATHERGS_TEST_THREADS");
  weathergs::set_num_threads(t ? std::atoi(t) : 0);
  return RUN_ALL_TESTS();
}
