// Clean renders must repeat. The benchmark scenes render with Cycles and must give the same bytes in
// every process, with any thread cap (docs/scenes.md, "One benchmark, bit for bit"); the training
// scenes keep EEVEE, which repeats only to within noise (llvmpipe), whose bar is 40 dB PSNR.
#include <gtest/gtest.h>

#include <cmath>

#include "core/dataset.h"
#include "core/image.h"
#include "core/sha256.h"
#include "capture/blender.h"
#include "capture/process.h"
#include "tests/core/test_util.h"

namespace weathergs::capture {
namespace {

using testing::TempDir;
constexpr double kMinRepeatPsnrDb = 40.0;  // the required bar for clean ground truth

std::string scene_file(const std::string& rel) { return std::string(WEATHERGS_SOURCE_DIR) + "/scenes/" + rel; }

// Every benchmark scene type (tanabata's lanterns are emitters, pool's and factory's curved props),
// rendered by one process on one thread and by two one-thread processes: the same files.
TEST(RenderRepeatabilityTest, CyclesRendersOfTheBenchmarkScenesAreIdenticalWithAnyThreadCap) {
  if (find_executable("blender").empty()) GTEST_SKIP() << "blender not installed";
  for (const char* name : {"tanabata.json", "factory.json", "pool.json"}) {
    const SceneSpec scene = read_scene_spec(scene_file(name));
    ASSERT_EQ(scene.profile("tiny").engine, "cycles") << name;
    TempDir tmp;
    BlenderOptions o;
    o.script = testing::blender_script();
    o.max_views = 3;
    o.threads = 1;
    render_clean_dataset(scene, "rain", "tiny", tmp / "a", o);
    o.threads = 2;
    render_clean_dataset(scene, "rain", "tiny", tmp / "b", o);
    const Dataset a = read_dataset(tmp / "a"), b = read_dataset(tmp / "b");
    for (const Camera& c : a.cameras)
      for (ImageKind k : {ImageKind::kClean, ImageKind::kDepth})
        EXPECT_EQ(sha256_file(a.path(k, c.name)), sha256_file(b.path(k, c.name))) << name << " " << to_string(k) << " " << c.name;
  }
}

TEST(RenderRepeatabilityTest, EeveeRendersOfATrainingSceneAgreeWithinNoise) {
  if (find_executable("blender").empty()) GTEST_SKIP() << "blender not installed";
  const SceneSpec scene = read_scene_spec(scene_file("training/village.json"));
  ASSERT_EQ(scene.profile("tiny").engine, "eevee");
  TempDir tmp;
  BlenderOptions o;
  o.script = testing::blender_script();
  o.max_views = 2;
  render_clean_dataset(scene, "clear", "tiny", tmp / "a", o);
  o.threads = 1;
  render_clean_dataset(scene, "clear", "tiny", tmp / "b", o);
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
