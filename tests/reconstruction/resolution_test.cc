// The resolution schedule: its factors, the box-downsampled views and cameras, the loss gradient
// through a downsampled render against finite differences, and the trainer's use of it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <functional>

#include "core/parallel.h"
#include "core/rng.h"
#include "tests/core/test_util.h"
#include "reconstruction/loss.h"
#include "reconstruction/rasterizer.h"
#include "reconstruction/resolution.h"
#include "reconstruction/trainer.h"
#include "tests/reconstruction/test_scene.h"

namespace weathergs::reconstruction {
namespace {

using testing::look_at_camera;
using testing::random_gaussians;

TEST(ResolutionTest, FactorHalvesAtEqualStepsAndEndsAtFullResolution) {
  // 4 -> 2 -> 1 over the first half of 7000 iterations.
  EXPECT_EQ(downsample_factor(4, 0.5, 7000, 1), 4);
  EXPECT_EQ(downsample_factor(4, 0.5, 7000, 1749), 4);
  EXPECT_EQ(downsample_factor(4, 0.5, 7000, 1750), 2);
  EXPECT_EQ(downsample_factor(4, 0.5, 7000, 3499), 2);
  EXPECT_EQ(downsample_factor(4, 0.5, 7000, 3500), 1);
  EXPECT_EQ(downsample_factor(4, 0.5, 7000, 7000), 1);
  // 8: three equal steps; full_at 1 still ends on a full-resolution iteration.
  EXPECT_EQ(downsample_factor(8, 1.0, 300, 99), 8);
  EXPECT_EQ(downsample_factor(8, 1.0, 300, 100), 4);
  EXPECT_EQ(downsample_factor(8, 1.0, 300, 200), 2);
  EXPECT_EQ(downsample_factor(8, 1.0, 300, 299), 2);
  EXPECT_EQ(downsample_factor(8, 1.0, 300, 300), 1);
  for (int it = 1; it <= 50; ++it) EXPECT_EQ(downsample_factor(1, 0.5, 50, it), 1);
  EXPECT_TRUE(is_downsample_factor(16));
  EXPECT_FALSE(is_downsample_factor(3));
  EXPECT_FALSE(is_downsample_factor(0));
}

TEST(ResolutionTest, DownsampledViewIsTheBlockMeanAndMasksAnyMaskedBlock) {
  TrainView v;
  v.camera = look_at_camera("c", 9, 6, 8.0, Eigen::Vector3d(0, -4, 1));  // 9 x 6: a partial column
  v.rgb.resize(9 * 6 * 3);
  for (size_t i = 0; i < v.rgb.size(); ++i) v.rgb[i] = float(i % 17) / 16.f;
  v.invalid.assign(9 * 6, 0);
  v.invalid[1 * 9 + 3] = 1;  // in block (1, 0) of the factor-2 grid
  const TrainView d = downsample_view(v, 2);
  ASSERT_EQ(d.camera.width, 4);
  ASSERT_EQ(d.camera.height, 3);
  ASSERT_EQ(d.rgb.size(), 4u * 3 * 3);
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x)
      for (int c = 0; c < 3; ++c) {
        float sum = 0;
        for (int dy = 0; dy < 2; ++dy)
          for (int dx = 0; dx < 2; ++dx) sum += v.rgb[(size_t(2 * y + dy) * 9 + 2 * x + dx) * 3 + c];
        EXPECT_FLOAT_EQ(d.rgb[(size_t(y) * 4 + x) * 3 + c], sum / 4) << x << "," << y;
      }
  for (int p = 0; p < 12; ++p) EXPECT_EQ(d.invalid[size_t(p)], p == 1 ? 1 : 0) << p;
  // A point lands on the same place of the image at either size: u' = u / f.
  const Eigen::Vector3d world(0.3, 0.2, 0.7);
  const Eigen::Vector2d full = *v.camera.project(world), half = *d.camera.project(world);
  EXPECT_NEAR(half.x(), full.x() / 2, 1e-12);
  EXPECT_NEAR(half.y(), full.y() / 2, 1e-12);
  const TrainView same = downsample_view(v, 1);
  EXPECT_EQ(same.rgb, v.rgb);
  EXPECT_EQ(same.invalid, v.invalid);
}

// The operator a downsampled iteration differentiates: the masked L1 + D-SSIM loss of a render at the
// downsampled camera against the box-downsampled target. Tolerances as tests/reconstruction/gradients.
TEST(ResolutionTest, DownsampledLossGradientMatchesFiniteDifferences) {
  constexpr double kStep = 1e-6, kRel = 1e-6, kAbs = 1e-8;
  TrainView full;
  full.camera = look_at_camera("c", 48, 36, 43.0, Eigen::Vector3d(0.3, -3.5, 1.0));
  Rng rng(9, 0, 0);
  full.rgb.resize(48 * 36 * 3);
  for (float& x : full.rgb) x = float(rng.uniform_double());
  full.invalid.assign(48 * 36, 0);
  for (int y = 10; y < 15; ++y) full.invalid[size_t(y) * 48 + 20] = 1;
  const TrainView low = downsample_view(full, 4);
  const std::vector<double> target(low.rgb.begin(), low.rgb.end());
  RasterCamera<double> cam = RasterCamera<double>::from(low.camera);
  cam.low_pass = kLowPass2d / 16;  // as the trainer renders at factor 4
  GaussianSet<double> g = random_gaussians<double>(20, 13, 0.7, 0.25, 0.2);
  RasterSettings<double> rs;
  RasterState<double> st;
  auto loss = [&](std::vector<double>* v_image) {
    rasterize_forward(g, cam, rs, &st);
    return double(photometric_loss<double>(st.image, target, &low.invalid, low.camera.width, low.camera.height,
                                           kLambdaDssim, v_image).loss);
  };
  std::vector<double> v_image;
  loss(&v_image);
  GaussianSet<double> grad;
  rasterize_backward(g, cam, rs, &st, v_image, &grad);
  auto f = [&] { return loss(nullptr); };
  auto fd = [&](double* x) {
    const double x0 = *x;
    *x = x0 + kStep;
    const double fp = f();
    *x = x0 - kStep;
    const double fm = f();
    *x = x0;
    return (fp - fm) / (2 * kStep);
  };
  int compared = 0;
  for (size_t i = 0; i < g.size(); i += 2) {
    for (int k = 0; k < 3; ++k) {
      const double a = grad.position[i * 3 + k], n = fd(&g.position[i * 3 + k]);
      EXPECT_NEAR(a, n, kAbs + kRel * (std::abs(a) + std::abs(n))) << "position of Gaussian " << i;
      const double as = grad.log_scale[i * 3 + k], ns = fd(&g.log_scale[i * 3 + k]);
      EXPECT_NEAR(as, ns, kAbs + kRel * (std::abs(as) + std::abs(ns))) << "log_scale of Gaussian " << i;
      compared += std::abs(a) > 1e-6;
    }
    const double ao = grad.opacity_logit[i], no = fd(&g.opacity_logit[i]);
    EXPECT_NEAR(ao, no, kAbs + kRel * (std::abs(ao) + std::abs(no))) << "opacity of Gaussian " << i;
  }
  EXPECT_GT(compared, 10);  // the Gaussians are in view of the 12 x 9 image
}

// A run set to start at 1/4 trains at 1/4, 1/2, then full resolution, with the budget shrunk by the
// factor squared; it gives the same bits on 1 and 2 threads and resumes mid-schedule to the
// uninterrupted model. The default never downsamples, and the methods with per-pixel state refuse it.
TEST(ResolutionTest, DownsampledRunIsDeterministicAndResumes) {
  const GaussianSet<float> truth = random_gaussians<float>(120, 3, 1.0, 0.1, 0.0);
  std::vector<TrainView> views;
  for (const Camera& cam : testing::ring_cameras(4, 32, 24, 29.0, 4.0)) {
    RasterState<float> st;
    rasterize_forward(truth, RasterCamera<float>::from(cam), RasterSettings<float>{}, &st);
    TrainView v;
    v.camera = cam;
    v.rgb = st.image;
    for (float& x : v.rgb) x = std::clamp(x, 0.f, 1.f);
    views.push_back(std::move(v));
  }
  GaussianSet<float> init = random_gaussians<float>(30, 2, 1.0, 0.1, 0.0);
  std::vector<Camera> cams;
  for (const TrainView& v : views) cams.push_back(v.camera);
  const double extent = scene_extent(cams);
  TrainOptions o;
  o.iterations = 60;
  o.downsample_start = 4;
  o.densify_from = 5;
  o.densify_until = 60;
  o.densification_interval = 5;
  o.densify_grad_threshold = 2e-5;  // low enough that Gaussians are cloned and split
  o.max_gaussians = 320;            // 20 at 1/4, 80 at 1/2
  weathergs::testing::TempDir dir;
  auto run = [&](int threads, int stop_at, const std::string& resume_from, std::vector<int>* factors,
                 std::vector<size_t>* sizes) {
    set_num_threads(threads);
    Trainer t(views, init, o, extent);
    if (!resume_from.empty()) t.load_checkpoint(resume_from);
    while (t.iteration() < stop_at) {
      const IterationStats st = t.step();
      if (factors) factors->push_back(st.downsample);
      if (sizes) sizes->push_back(size_t(st.num_gaussians));
    }
    return t;
  };
  std::vector<int> f;
  std::vector<size_t> n;
  const Trainer one = run(1, 60, "", &f, &n);
  EXPECT_EQ(f[0], 4);
  EXPECT_EQ(f[14], 2);  // iteration 15 = 0.5 x 60 / 2
  EXPECT_EQ(f[29], 1);  // iteration 30 = 0.5 x 60
  EXPECT_EQ(f.back(), 1);
  // It starts with 30: the 1/4 budget (320 / 16 = 20) lets nothing grow until 1/2 (80).
  EXPECT_LE(*std::max_element(n.begin(), n.begin() + 14), 30u);
  EXPECT_LE(*std::max_element(n.begin(), n.end()), 320u);
  EXPECT_GT(n.back(), 80u) << "the budget grows back with the resolution";
  const Trainer two = run(2, 60, "", nullptr, nullptr);
  EXPECT_EQ(one.gaussians().position, two.gaussians().position);
  EXPECT_EQ(one.gaussians().sh, two.gaussians().sh);
  run(1, 10, "", nullptr, nullptr).save_checkpoint(dir / "low.bin", 1.0);  // inside the 1/4 phase
  const Trainer resumed = run(2, 60, dir / "low.bin", nullptr, nullptr);
  set_num_threads(0);
  EXPECT_EQ(one.gaussians().position, resumed.gaussians().position);
  EXPECT_EQ(one.gaussians().opacity_logit, resumed.gaussians().opacity_logit);

  for (TrainOptions::Schedule s : {TrainOptions::Schedule::kFast, TrainOptions::Schedule::kReference}) {
    TrainOptions d;
    d.schedule = s;
    d.iterations = 8;
    Trainer t(views, init, d, extent);
    for (int i = 0; i < 8; ++i) EXPECT_EQ(t.step().downsample, 1) << to_string(s);
  }
  TrainOptions wild;
  wild.in_the_wild = true;
  wild.downsample_start = 2;
  EXPECT_THROW(wild.validate("x"), InputError);
  TrainOptions robust;
  robust.robust = TrainOptions::Robust::kRobustFilter;
  robust.downsample_start = 2;
  EXPECT_THROW(robust.validate("x"), InputError);
  TrainOptions bad;
  bad.downsample_start = 3;
  EXPECT_THROW(bad.validate("x"), InputError);
  bad.downsample_start = 0;
  EXPECT_THROW(bad.validate("x"), InputError);
  bad.downsample_start = 2;
  bad.full_resolution_at = 0;
  EXPECT_THROW(bad.validate("x"), InputError);
}

// The trainer itself (not only the operator above) renders a downsampled iteration at the downsampled
// camera with the scaled low-pass: its first iteration's loss at factor 4 is, bit for bit, the loss of
// that render against the box-downsampled view, and not the one with the full-resolution low-pass.
TEST(ResolutionTest, TheTrainerRendersADownsampledIterationWithTheScaledLowPass) {
  const GaussianSet<float> truth = random_gaussians<float>(120, 3, 1.0, 0.1, 0.0);
  std::vector<TrainView> views;
  for (const Camera& cam : testing::ring_cameras(4, 64, 48, 58.0, 4.0)) {
    TrainView v;
    v.camera = cam;
    v.rgb = testing::render_image(truth, cam).data;
    views.push_back(std::move(v));
  }
  std::vector<Camera> cams;
  for (const TrainView& v : views) cams.push_back(v.camera);
  // Small Gaussians (~1 px at full size): at 1/4 the low-pass is most of their footprint.
  const GaussianSet<float> init = random_gaussians<float>(200, 4, 1.0, 0.01, 0.0);
  TrainOptions o;
  o.iterations = 40;
  o.downsample_start = 4;
  Trainer t(views, init, o, scene_extent(cams));
  const IterationStats st = t.step();
  ASSERT_EQ(st.downsample, 4);
  const TrainView low = downsample_view(views[size_t(t.view_for_iteration(1))], 4);
  auto loss_with = [&](double low_pass) {
    RasterCamera<float> cam = RasterCamera<float>::from(low.camera);
    cam.low_pass = float(low_pass);
    RasterSettings<float> rs;
    rs.sh_degree = t.sh_degree();
    RasterState<float> state;
    rasterize_forward(init, cam, rs, &state);
    return double(photometric_loss<float>(state.image, low.rgb, nullptr, low.camera.width, low.camera.height,
                                          float(kLambdaDssim), nullptr, MaskNormalization::kValid)
                      .loss);
  };
  const double scaled = loss_with(kLowPass2d / 16), unscaled = loss_with(kLowPass2d);
  std::printf("first iteration at 1/4: trainer loss %.6f, scaled low-pass %.6f, unscaled %.6f\n", st.loss, scaled,
              unscaled);
  EXPECT_EQ(st.loss, scaled);
  EXPECT_GT(std::abs(unscaled - scaled), 1e-3) << "the test must tell the two low-passes apart";
}

// Why the low-pass scales with the factor: small Gaussians rendered at factor 4 with the full-resolution
// pixel's footprint (0.3 / 16 px^2) carry the light of the box-downsampled full-resolution render; with
// the reference's 0.3 px^2 each would cover 16 times the scene it covers at full size, so a model
// fitted at 1/4 would be too dark at full resolution.
TEST(ResolutionTest, ScaledLowPassKeepsSmallGaussiansAsBrightAsAtFullResolution) {
  const Camera full = look_at_camera("c", 96, 72, 90.0, Eigen::Vector3d(0.3, -3.5, 1.0));
  const Camera low = downsample_camera(full, 4);
  const GaussianSet<float> g = random_gaussians<float>(400, 21, 0.8, 0.004, 0.0);  // ~0.1 px at full size
  RasterSettings<float> rs;
  RasterState<float> st;
  rasterize_forward(g, RasterCamera<float>::from(full), rs, &st);
  TrainView v;
  v.camera = full;
  v.rgb = st.image;
  const std::vector<float> target = downsample_view(v, 4).rgb;
  auto mean = [](const std::vector<float>& a) {
    double s = 0;
    for (float x : a) s += x;
    return s / double(a.size());
  };
  auto rendered = [&](double low_pass) {
    RasterCamera<float> cam = RasterCamera<float>::from(low);
    cam.low_pass = float(low_pass);
    rasterize_forward(g, cam, rs, &st);
    return mean(st.image);
  };
  const double want = mean(target), scaled = rendered(kLowPass2d / 16), reference = rendered(kLowPass2d);
  std::printf("mean intensity at 1/4: box mean of the full render %.4f, scaled low-pass %.4f, unscaled %.4f\n", want,
              scaled, reference);
  // Point samples of the same footprints: within sampling noise of the block means (400 Gaussians
  // on 432 pixels); the unscaled footprint overstates the light several times over.
  EXPECT_NEAR(scaled / want, 1.0, 0.1) << "scaled " << scaled << ", box mean " << want;
  EXPECT_GT(reference / want, 3.0) << "unscaled " << reference << ", box mean " << want;
}

}  // namespace
}  // namespace weathergs::reconstruction
