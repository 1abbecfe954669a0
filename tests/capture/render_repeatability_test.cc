// Clean images must be noise-free: two renders of one view agree to at least 40 dB PSNR (the required
// bar). EEVEE has no sampling seed; two separate Blender processes are the repeat that matters
// (thread timing in llvmpipe is the only source of differences). The second one runs capped at one
// thread (BlenderOptions::threads, `weathergs -j 1 generate`): the cap must not change the image.
#include <gtest/gtest.h>

#include <cmath>

#include "core/dataset.h"
#include "core/image.h"
#include "capture/blender.h"
#include "capture/process.h"
#include "tests/core/test_util.h"

namespace weathergs::capture {
namespace {

using testing::TempDir;
constexpr double kMinRepeatPsnrDb = 40.0;  // the required bar for clean ground truth

TEST(RenderRepeatabilityTest, TwoProcessesAgree) {
  if (find_executable("blender").empty()) GTEST_SKIP() << "blender not installed";
  const SceneSpec scene = read_scene_spec(std::string(WEATHERGS_SOURCE_DIR) + "/scenes/factory.json");
  TempDir tmp;
  BlenderOptions o;
  o.script = testing::blender_script();
  o.max_views = 2;
  render_clean_dataset(scene, "snow", "tiny", tmp / "a", o);
  o.threads = 1;
  render_clean_dataset(scene, "snow", "tiny", tmp / "b", o);
  const Dataset a = read_dataset(tmp / "a");
  for (const Camera& c : a.cameras) {
    const Image x = read_image(a.path(ImageKind::kClean, c.name));
    const Image y = read_image(tmp / ("b/clean/" + c.name + ".png"));
    ASSERT_TRUE(x.same_shape(y));
    double mse = 0;
    for (size_t i = 0; i < x.data.size(); ++i) mse += double(x.data[i] - y.data[i]) * (x.data[i] - y.data[i]);
    mse /= double(x.data.size());
    const double psnr = mse > 0 ? 10 * std::log10(1.0 / mse) : 99.0;
    EXPECT_GE(psnr, kMinRepeatPsnrDb) << c.name;
    std::printf("view %s: repeat PSNR %.1f dB\n", c.name.c_str(), psnr);
  }
}

}  // namespace
}  // namespace weathergs::capture
