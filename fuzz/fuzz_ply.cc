// The 3DGS PLY reader (reconstruction/gaussians.h).
#include "fuzz/fuzz_common.h"
#include "reconstruction/gaussians.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace weathergs;
  const std::string path = fuzz::write_input(data, size, "point_cloud.ply");
  return fuzz::expect_only_input_errors([&] { reconstruction::read_ply(path); });
}
