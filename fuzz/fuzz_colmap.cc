// COLMAP text models (core/colmap_model.h). The first byte picks the file the input becomes; the other
// two files of the model are valid minimal ones.
#include <filesystem>

#include "core/colmap_model.h"
#include "fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace weathergs;
  if (size < 1) return 0;
  const std::string dir = fuzz::scratch_dir() + "/model";
  std::filesystem::create_directories(dir);
  const char* files[3] = {"cameras.txt", "images.txt", "points3D.txt"};
  const int which = data[0] % 3;
  const uint8_t ok_cameras[] = "1 PINHOLE 64 48 50 50 32 24\n";
  const uint8_t ok_images[] = "1 1 0 0 0 0 0 0 1 a.png\n\n";
  const uint8_t ok_points[] = "1 0 0 1 255 0 0 0.5 1 0\n";
  fuzz::write_input(ok_cameras, sizeof(ok_cameras) - 1, "model/cameras.txt");
  fuzz::write_input(ok_images, sizeof(ok_images) - 1, "model/images.txt");
  fuzz::write_input(ok_points, sizeof(ok_points) - 1, "model/points3D.txt");
  fuzz::write_input(data + 1, size - 1, std::string("model/") + files[which]);
  return fuzz::expect_only_input_errors([&] {
    read_colmap_text(dir);
    read_colmap_points3d(dir + "/points3D.txt");
  });
}
