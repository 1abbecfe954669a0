// Scene specs (capture/scene_spec.h), including the camera paths of every profile.
#include "capture/scene_spec.h"
#include "fuzz/fuzz_common.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace weathergs;
  const std::string path = fuzz::write_input(data, size, "scene.json");
  return fuzz::expect_only_input_errors([&] {
    const capture::SceneSpec s = capture::read_scene_spec(path);
    for (const auto& [name, profile] : s.profiles) capture::scene_cameras(s, profile);
  });
}
