// The radiance-field trainer (nerf/trainer.h): it fits a toy scene, it is deterministic across
// thread counts, masked pixels never reach the loss, coarse-to-fine keeps going, bad options fail.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/parallel.h"
#include "nerf/trainer.h"
#include "tests/nerf/test_scene.h"

namespace weathergs::nerf {
namespace {

using testing::cams;
using testing::plane_views;

NerfOptions small_options(int iterations) {
  NerfOptions o;
  o.iterations = iterations;
  o.batch_rays = 512;
  o.seed = 4;
  o.pixels_per_cell = 2;
  o.depth_cells = 24;
  o.level_scales = {0.5, 1.0};
  o.upsample_at = {iterations / 3};
  return o;
}

TEST(NerfTrainerTest, FitsAToyPlaneAndTheLossFalls) {
  const std::vector<TrainView> views = plane_views();
  const FrustumFrame frame = forward_facing_frame(cams(views), 1.5);
  NerfTrainer t(views, frame, small_options(300));
  double first = 0, last = 0;
  GridDims before = t.field().dims();
  for (int i = 0; i < 300; ++i) {
    const NerfIterationStats st = t.step();
    ASSERT_TRUE(std::isfinite(st.loss));
    if (i < 10) first += st.loss / 10;
    if (i >= 290) last += st.loss / 10;
  }
  EXPECT_LT(last, 0.1 * first) << "first " << first << " last " << last;
  EXPECT_GT(t.field().dims().points(), before.points());  // the upsample happened
  // The fitted field renders a training view well (PSNR > 25 dB; the toy is smooth).
  const std::vector<float> img = t.field().render(views[1].camera, t.options().march);
  double mse = 0;
  for (size_t i = 0; i < img.size(); ++i) mse += (img[i] - views[1].rgb[i]) * (img[i] - views[1].rgb[i]);
  mse /= double(img.size());
  EXPECT_GT(-10 * std::log10(mse), 25.0);
}

TEST(NerfTrainerTest, SameSeedSameFieldWithOneOrTwoThreads) {
  const std::vector<TrainView> views = plane_views();
  const FrustumFrame frame = forward_facing_frame(cams(views), 1.5);
  std::vector<std::vector<float>> params;
  for (int threads : {1, 2}) {
    set_num_threads(threads);
    NerfTrainer t(views, frame, small_options(40));
    for (int i = 0; i < 40; ++i) t.step();
    params.push_back(t.field().params());
    params.back().insert(params.back().end(), t.field().env().begin(), t.field().env().end());
  }
  set_num_threads(0);
  EXPECT_TRUE(params[0] == params[1]);
}

TEST(NerfTrainerTest, MaskedPixelsNeverReachTheLoss) {
  std::vector<TrainView> a = plane_views(), b = plane_views();
  for (size_t v = 0; v < a.size(); ++v) {
    const size_t n = a[v].rgb.size() / 3;
    a[v].invalid.assign(n, 0);
    for (size_t p = 0; p < n; p += 3) a[v].invalid[p] = 1;
    b[v].invalid = a[v].invalid;
    for (size_t p = 0; p < n; p += 3)
      for (int ch = 0; ch < 3; ++ch) {
        a[v].rgb[p * 3 + ch] = 0.f;
        b[v].rgb[p * 3 + ch] = std::nanf("");  // would poison the loss if it were read
      }
  }
  const FrustumFrame frame = forward_facing_frame(cams(a), 1.5);
  NerfTrainer ta(a, frame, small_options(20)), tb(b, frame, small_options(20));
  for (int i = 0; i < 20; ++i) {
    ta.step();
    EXPECT_TRUE(std::isfinite(tb.step().loss));
  }
  EXPECT_TRUE(ta.field().params() == tb.field().params());
  // Everything masked: a clear error.
  for (TrainView& v : a) v.invalid.assign(v.invalid.size(), 1);
  EXPECT_THROW(NerfTrainer(a, frame, small_options(5)), InputError);
}

TEST(NerfTrainerTest, OptionsAreValidated) {
  NerfOptions o;
  o.level_scales = {0.5, 0.9};
  EXPECT_THROW(o.validate("o"), InputError);
  o = NerfOptions{};
  o.upsample_at = {1000};
  EXPECT_THROW(o.validate("o"), InputError);
  o = NerfOptions{};
  o.batch_rays = 0;
  EXPECT_THROW(o.validate("o"), InputError);
  o = NerfOptions{};
  EXPECT_NO_THROW(o.validate("o"));
  // Round trip through JSON.
  const Json j = o.to_json();
  const NerfOptions back = NerfOptions::from_json(JsonReader(j, "options.json"));
  EXPECT_EQ(back.to_json(), j);
}

}  // namespace
}  // namespace weathergs::nerf
