// Image headers and pixels through core's reader (OpenImageIO): PNG, EXR (depth) and masks. The first
// byte picks the extension and the reader.
#include "core/image.h"
#include "fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace weathergs;
  if (size < 1) return 0;
  const int which = data[0] % 3;
  const std::string path = fuzz::write_input(data + 1, size - 1, which == 1 ? "depth.exr" : "image.png");
  return fuzz::expect_only_input_errors([&] {
    if (which == 0) read_image(path);
    else if (which == 1) read_depth(path);
    else read_mask(path);
  });
}
