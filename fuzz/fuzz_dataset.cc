// dataset.json and cameras.json readers (core/dataset.h). The first byte picks the reader.
#include "core/dataset.h"
#include "fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace weathergs;
  if (size < 1) return 0;
  const bool cameras = data[0] & 1;
  const std::string path = fuzz::write_input(data + 1, size - 1, cameras ? "cameras.json" : "dataset.json");
  return fuzz::expect_only_input_errors([&] {
    if (cameras) read_cameras_json(path);
    else read_dataset_json(path);
  });
}
