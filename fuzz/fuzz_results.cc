// Results files (evaluator/results.h): what leaderboard and check read.
#include "evaluator/results.h"
#include "fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace weathergs;
  const std::string path = fuzz::write_input(data, size, "results.json");
  return fuzz::expect_only_input_errors([&] { evaluator::read_results(path); });
}
