// Rasterizer: equality with a per-pixel reference blend, float vs double, hard cases, determinism.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "core/parallel.h"
#include "core/rng.h"
#include "reconstruction/loss.h"
#include "reconstruction/raster_internal.h"
#include "reconstruction/rasterizer.h"
#include "tests/reconstruction/test_scene.h"

namespace weathergs::reconstruction {
namespace {

using testing::look_at_camera;
using testing::random_gaussians;

Camera front_camera(int w, int h) { return look_at_camera("c", w, h, 0.9 * w, Eigen::Vector3d(0.2, -4, 0.5)); }

// The reference's blend weight of Gaussian gi at pixel (x, y), or 0 where the blend skips it
// (power > 0 or alpha < 1/255): written independently of the tile kernels.
double reference_alpha(const RasterState<double>& st, int gi, int x, int y) {
  const double dx = st.mean2d[gi * 2] - (x + 0.5), dy = st.mean2d[gi * 2 + 1] - (y + 0.5);
  const double power =
      -0.5 * (st.conic[gi * 3] * dx * dx + st.conic[gi * 3 + 2] * dy * dy) - st.conic[gi * 3 + 1] * dx * dy;
  if (power > 0) return 0;
  const double alpha = std::min(0.99, st.opacity[gi] * std::exp(power));
  return alpha < 1.0 / 255 ? 0 : alpha;
}

// The reference per-pixel loop (every Gaussian of the pixel's tile list whose record's pixel box
// holds the pixel, no other bound), written independently of the tile kernel.
TEST(RasterizerTest, TileKernelEqualsPerPixelReferenceBlend) {
  const Camera c = front_camera(70, 45);
  const RasterCamera<double> cam = RasterCamera<double>::from(c);
  const GaussianSet<double> g = random_gaussians<double>(400, 21, 1.0, 0.08, 0.2);
  RasterSettings<double> rs;
  rs.background = {0.1, 0.3, 0.6};
  RasterState<double> st;
  rasterize_forward(g, cam, rs, &st);
  int64_t max_list = 0;
  for (int t = 0; t < st.tiles_x * st.tiles_y; ++t) {
    const int64_t b = st.tile_offset[t], e = st.tile_offset[t + 1];
    max_list = std::max(max_list, e - b);
    for (int64_t k = b + 1; k < e; ++k)
      ASSERT_LE(float(st.depth[st.tile_gaussian[k - 1]]),
                float(st.depth[st.tile_gaussian[k]])) << "tile " << t;
  }
  EXPECT_GT(max_list, 50);
  int stopped_pixels = 0;
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x) {
      const int t = (y / kTileSize) * st.tiles_x + x / kTileSize;
      double T = 1, rgb[3] = {0, 0, 0};
      int last = 0;
      for (int64_t k = st.tile_offset[t]; k < st.tile_offset[t + 1]; ++k) {
        const int gi = st.tile_gaussian[k];
        const double* box = &st.splat[int64_t(gi) * kSplatFloats + 12];
        if (x < box[0] || x > box[1] || y < box[2] || y > box[3]) continue;
        const double alpha = reference_alpha(st, gi, x, y);
        if (alpha == 0) continue;
        const double test_t = T * (1 - alpha);
        if (test_t < 1e-4) { ++stopped_pixels; break; }
        for (int ch = 0; ch < 3; ++ch) rgb[ch] += st.color[gi * 3 + ch] * alpha * T;
        T = test_t;
        last = int(k - st.tile_offset[t] + 1);
      }
      const int64_t pix = int64_t(y) * c.width + x;
      for (int ch = 0; ch < 3; ++ch)
        ASSERT_NEAR(st.image[pix * 3 + ch], rgb[ch] + T * rs.background[ch], 1e-12) << x << "," << y;
      ASSERT_NEAR(st.final_transmittance[pix], T, 1e-12);
      ASSERT_EQ(st.n_contrib[pix], last) << x << "," << y;
    }
  EXPECT_GT(stopped_pixels, 0);  // the transmittance stop was exercised
}

// The opacity-aware tile rectangles drop no pixel that the reference's 3-sigma tiles would blend:
// per pixel, the blend over every Gaussian whose 3-sigma tile rectangle (the reference's getRect)
// holds the pixel's tile, in depth order, equals the rasterizer's image. Low opacities and large
// splats make the trimmed rectangles much smaller than the 3-sigma ones.
TEST(RasterizerTest, OpacityAwareTilesKeepEveryContributingPixel) {
  const Camera c = front_camera(90, 61);
  const RasterCamera<double> cam = RasterCamera<double>::from(c);
  GaussianSet<double> g = random_gaussians<double>(300, 33, 1.0, 0.15, 0.2);
  for (size_t i = 0; i < g.size(); ++i)  // opacities from 0.001 to 0.9: many below the 3-sigma extent
    g.opacity_logit[i] = inverse_sigmoid(0.001 + 0.9 * double((i * 37) % 100) / 99.0);
  RasterState<double> st;
  rasterize_forward(g, cam, RasterSettings<double>{}, &st);
  std::vector<int> order;  // visible Gaussians by (depth, index), as the rasterizer sorts them
  double pixels_3sigma = 0, pixels_box = 0;
  std::vector<std::array<int, 4>> rect3(g.size());
  for (size_t i = 0; i < g.size(); ++i) {
    if (st.radius[i] == 0) continue;
    const double r = st.radius[i], px = st.mean2d[i * 2] - 0.5, py = st.mean2d[i * 2 + 1] - 0.5;
    // getRect on the reference's 16-px grid (kReferenceTile; the rasterizer bins into larger tiles)
    const int gx = (c.width + kReferenceTile - 1) / kReferenceTile, gy = (c.height + kReferenceTile - 1) / kReferenceTile;
    auto tile = [&](double v, int grid) { return std::clamp(int(std::floor(v / kReferenceTile)), 0, grid); };
    rect3[i] = {tile(px - r, gx), tile(py - r, gy), tile(px + r + kReferenceTile - 1, gx), tile(py + r + kReferenceTile - 1, gy)};
    pixels_3sigma += double(std::min(c.width, rect3[i][2] * kReferenceTile) - rect3[i][0] * kReferenceTile) *
                     (std::min(c.height, rect3[i][3] * kReferenceTile) - rect3[i][1] * kReferenceTile);
    const double* box = &st.splat[i * kSplatFloats + 12];
    pixels_box += std::max(0.0, box[1] - box[0] + 1) * std::max(0.0, box[3] - box[2] + 1);
    order.push_back(int(i));
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return float(st.depth[a]) < float(st.depth[b]); });
  EXPECT_LT(pixels_box, 0.9 * pixels_3sigma) << "the scene should exercise the trimming";
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x) {
      const int tx = x / kReferenceTile, ty = y / kReferenceTile;
      double T = 1, rgb[3] = {0, 0, 0};
      for (int gi : order) {
        const auto& r = rect3[gi];
        if (tx < r[0] || tx >= r[2] || ty < r[1] || ty >= r[3]) continue;
        const double alpha = reference_alpha(st, gi, x, y);
        if (alpha == 0) continue;
        const double test_t = T * (1 - alpha);
        if (test_t < 1e-4) break;
        for (int ch = 0; ch < 3; ++ch) rgb[ch] += st.color[gi * 3 + ch] * alpha * T;
        T = test_t;
      }
      const int64_t pix = int64_t(y) * c.width + x;
      for (int ch = 0; ch < 3; ++ch) ASSERT_NEAR(st.image[pix * 3 + ch], rgb[ch], 1e-12) << x << "," << y;
    }
}

// The float tile kernel skips an 8-pixel block when every lane's power lies below -sp[11] / 2 (the
// record's alpha bound with its margin). That is exact only if no power below it can give a kernel
// alpha >= 1/255: swept here over opacities from just above 1/255 to 1 and powers on a fine grid
// around each one's threshold ln(1 / (255 o)), with the kernel's own float arithmetic.
TEST(RasterizerTest, BlendSkipBoundIsConservative) {
  int near_threshold = 0;
  for (int i = 0; i <= 2000; ++i) {
    const float o = float(kAlphaMin) * (1.0f + 1e-6f) + (1.0f - float(kAlphaMin)) * float(i) / 2000.0f;
    const float q_max = internal::alpha_q_max(o);
    ASSERT_GE(q_max, 0.0f) << o;
    const float bound = -0.5f * (q_max * 1.0001f + 1e-3f);  // as sp[11] in finish_gaussian
    const float threshold = -0.5f * q_max;
    for (int k = -400; k <= 400; ++k) {
      const float power = threshold + float(k) * 2e-6f;
      const float alpha = std::min(float(kAlphaMax), o * internal::blend_exp(std::min(power, 0.0f)));
      if (alpha >= float(kAlphaMin)) {
        ASSERT_GE(power, bound) << "opacity " << o << ": alpha " << alpha << " at a power the kernel skips";
        near_threshold += power < threshold + 1e-4f;
      }
    }
  }
  EXPECT_GT(near_threshold, 1000);  // the sweep does reach alphas right at the threshold
}

// The float path (fast exp) against the double path on the same scene.
// The float blend exp (raster_internal.h) against std::exp in double: densely over the blend's range
// [-5.6, 0] (a weight >= 1/255 needs power >= -ln 255), at tiny arguments, and down to its -87 floor.
TEST(RasterizerTest, BlendExpIsAccurate) {
  constexpr double kBlendRangeTol = 6e-7;  // 4.4e-7 in a float emulation: the fit (9e-8) + x log2 e rounding
  constexpr double kFullRangeTol = 5e-6;   // 3.9e-6 near -87 (the rounding of x log2 e grows with |x|)
  double worst_blend = 0, worst_full = 0;
  auto err = [](float x) {
    const double ref = std::exp(double(x));
    return std::abs(double(internal::blend_exp(x)) - ref) / ref;
  };
  constexpr int kSamples = 2000000;
  for (int i = 0; i <= kSamples; ++i) worst_blend = std::max(worst_blend, err(-5.6f * float(i) / float(kSamples)));
  for (int k = 1; k < 126; ++k) worst_blend = std::max(worst_blend, err(-std::ldexp(1.f, -k)));
  for (int i = 0; i <= kSamples / 10; ++i)
    worst_full = std::max(worst_full, err(-87.f * float(i) / float(kSamples / 10)));
  EXPECT_LT(worst_blend, kBlendRangeTol);
  EXPECT_LT(worst_full, kFullRangeTol);
  EXPECT_EQ(internal::blend_exp(0.f), 1.f);
  EXPECT_GT(internal::blend_exp(-200.f), 0.f);  // clamped at -87, never 0 or NaN
  EXPECT_TRUE(std::isfinite(internal::blend_exp(-std::numeric_limits<float>::infinity())));
  std::printf("blend exp: max relative error %.2e on [-5.6, 0], %.2e on [-87, 0]\n", worst_blend, worst_full);
}

// model_exp and model_log (gaussian_math.h) against double libm, in units of the float spacing at
// the exact value (ulp). Cephes documents ~1 ulp for both on these ranges; 2 leaves room for the
// double rounding of the reference. Ranges: every float log scale and logit the trainer can reach
// (exp of -87..88) and the log of 255 x opacity (1 to 255), plus the whole normal range for log.
TEST(RasterizerTest, FloatExpAndLogAreAccurate) {
  constexpr double kMaxUlp = 2.0;
  auto ulp_error = [](float got, double ref) {
    int exponent;
    std::frexp(ref, &exponent);
    return std::abs(double(got) - ref) / std::ldexp(1.0, std::max(exponent, -125) - 24);
  };
  double worst_exp = 0, worst_log = 0;
  constexpr int kSamples = 2000000;
  for (int i = 0; i <= kSamples; ++i) {
    const float x = -87.f + 175.f * float(i) / float(kSamples);
    worst_exp = std::max(worst_exp, ulp_error(model_exp(x), std::exp(double(x))));
  }
  for (int i = 0; i <= kSamples; ++i) {
    const float x = 1.f + 254.f * float(i) / float(kSamples);
    worst_log = std::max(worst_log, ulp_error(model_log(x), std::log(double(x))));
  }
  for (int k = -126; k < 128; ++k)
    for (float m : {1.f, 1.2345f, 1.41421f, 1.5f, 1.999f}) {
      const float x = std::ldexp(m, k);
      if (x == 1.f) continue;  // log 1 = 0: no ulp scale (checked exactly below)
      worst_log = std::max(worst_log, ulp_error(model_log(x), std::log(double(x))));
    }
  EXPECT_LE(worst_exp, kMaxUlp);
  EXPECT_LE(worst_log, kMaxUlp);
  EXPECT_EQ(model_exp(0.f), 1.f);
  EXPECT_EQ(model_log(1.f), 0.f);
  EXPECT_GT(model_exp(-1000.f), 0.f);  // clamped at -87 and 88: finite, never 0
  EXPECT_TRUE(std::isfinite(model_exp(1000.f)));
  EXPECT_TRUE(std::isnan(model_exp(std::numeric_limits<float>::quiet_NaN())));
  EXPECT_EQ(sigmoid(0.f), 0.5f);
  EXPECT_EQ(sigmoid(-200.f), sigmoid(-87.f));  // no overflow or NaN at extreme logits
  EXPECT_EQ(sigmoid(200.f), 1.f);
  std::printf("model exp: max error %.2f ulp on [-87, 88]; model log: %.2f ulp\n", worst_exp, worst_log);
}

TEST(RasterizerTest, FloatMatchesDouble) {
  const Camera c = front_camera(64, 48);
  const GaussianSet<double> gd = random_gaussians<double>(300, 22, 1.0, 0.08, 0.2);
  const GaussianSet<float> gf = gd.cast<float>();
  RasterState<double> sd;
  RasterState<float> sf;
  rasterize_forward(gd, RasterCamera<double>::from(c), RasterSettings<double>{}, &sd);
  rasterize_forward(gf, RasterCamera<float>::from(c), RasterSettings<float>{}, &sf);
  // float rounding (~1e-7 per operation, a few hundred blended terms) and the 2-ulp exp.
  constexpr double kFloatTol = 2e-4;
  double max_err = 0;
  for (size_t i = 0; i < sd.image.size(); ++i) max_err = std::max(max_err, std::abs(sd.image[i] - double(sf.image[i])));
  EXPECT_LT(max_err, kFloatTol);
}

// The float backward (vectorized tile kernel, fast exp) against the double backward (scalar kernel).
TEST(RasterizerTest, FloatGradientsMatchDouble) {
  const Camera c = front_camera(64, 48);
  const GaussianSet<double> gd = random_gaussians<double>(300, 23, 1.0, 0.08, 0.2);
  const GaussianSet<float> gf = gd.cast<float>();
  RasterState<double> sd;
  RasterState<float> sf;
  const RasterCamera<double> cd = RasterCamera<double>::from(c);
  const RasterCamera<float> cf = RasterCamera<float>::from(c);
  rasterize_forward(gd, cd, RasterSettings<double>{}, &sd);
  rasterize_forward(gf, cf, RasterSettings<float>{}, &sf);
  std::vector<double> wd(sd.image.size());
  Rng rng(3, 0, 0);
  for (double& w : wd) w = rng.uniform_double() - 0.5;
  const std::vector<float> wf(wd.begin(), wd.end());
  GaussianSet<double> grad_d;
  GaussianSet<float> grad_f;
  rasterize_backward(gd, cd, RasterSettings<double>{}, &sd, wd, &grad_d);
  rasterize_backward(gf, cf, RasterSettings<float>{}, &sf, wf, &grad_f);
  // Relative to the largest gradient of each kind: float sums of a few thousand terms.
  constexpr double kFloatGradTol = 2e-3;
  auto compare = [&](const std::vector<double>& a, const std::vector<float>& b, const char* name) {
    double scale = 0, err = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      scale = std::max(scale, std::abs(a[i]));
      err = std::max(err, std::abs(a[i] - double(b[i])));
    }
    EXPECT_GT(scale, 0) << name;
    EXPECT_LT(err, kFloatGradTol * scale) << name;
  };
  compare(grad_d.position, grad_f.position, "position");
  compare(grad_d.log_scale, grad_f.log_scale, "log_scale");
  compare(grad_d.rotation, grad_f.rotation, "rotation");
  compare(grad_d.opacity_logit, grad_f.opacity_logit, "opacity");
  compare(grad_d.sh, grad_f.sh, "sh");
}

// Forward, loss and backward on a scene, asserting every output is finite.
void expect_finite_pipeline(const GaussianSet<float>& g, const Camera& c, const std::string& what) {
  RasterState<float> st;
  RasterSettings<float> rs;
  const RasterCamera<float> cam = RasterCamera<float>::from(c);
  rasterize_forward(g, cam, rs, &st);
  std::vector<float> target(st.image.size(), 0.5f), v;
  photometric_loss<float>(st.image, target, nullptr, c.width, c.height, 0.2f, &v);
  GaussianSet<float> grad;
  std::vector<float> ndc;
  rasterize_backward(g, cam, rs, &st, v, &grad, &ndc);
  auto finite = [&](const std::vector<float>& a, const char* name) {
    for (size_t i = 0; i < a.size(); ++i) ASSERT_TRUE(std::isfinite(a[i])) << what << ": " << name << "[" << i << "]";
  };
  finite(st.image, "image");
  finite(v, "dL/dimage");
  finite(grad.position, "position");
  finite(grad.log_scale, "log_scale");
  finite(grad.rotation, "rotation");
  finite(grad.opacity_logit, "opacity");
  finite(grad.sh, "sh");
  finite(ndc, "ndc");
}

GaussianSet<float> one_gaussian(Eigen::Vector3f p, Eigen::Vector3f log_scale, Eigen::Vector4f q, float logit) {
  GaussianSet<float> g;
  g.assign_zero(1);
  for (int k = 0; k < 3; ++k) {
    g.position[k] = p[k];
    g.log_scale[k] = log_scale[k];
    g.sh[k] = 1.f;
  }
  for (int k = 0; k < 4; ++k) g.rotation[k] = q[k];
  g.opacity_logit[0] = logit;
  return g;
}

TEST(RasterizerTest, HardCasesStayFinite) {
  const Camera c = front_camera(48, 32);
  const Eigen::Vector3f center(0, 0, 0);
  const Eigen::Vector4f id(1, 0, 0, 0);
  const float ls = std::log(0.1f);
  // The camera is at (0.2, -4, 0.5) looking at the origin: y = -4 + d is at depth ~d.
  struct Case { const char* name; GaussianSet<float> g; };
  std::vector<Case> cases = {
      {"scale 1e-8", one_gaussian(center, Eigen::Vector3f::Constant(std::log(1e-8f)), id, 0)},
      {"scale 1e4", one_gaussian(center, Eigen::Vector3f::Constant(std::log(1e4f)), id, 0)},
      {"zero quaternion", one_gaussian(center, Eigen::Vector3f::Constant(ls), Eigen::Vector4f::Zero(), 0)},
      {"denormal quaternion", one_gaussian(center, Eigen::Vector3f::Constant(ls), Eigen::Vector4f::Constant(1e-40f), 0)},
      {"behind the camera", one_gaussian(Eigen::Vector3f(0.2f, -5, 0.5f), Eigen::Vector3f::Constant(ls), id, 0)},
      {"at the near plane", one_gaussian(Eigen::Vector3f(0.2f, -3.8f, 0.5f), Eigen::Vector3f::Constant(ls), id, 0)},
      {"straddling the near plane", one_gaussian(Eigen::Vector3f(0.2f, -3.7f, 0.5f), Eigen::Vector3f::Constant(std::log(0.5f)), id, 0)},
      {"flat", one_gaussian(center, Eigen::Vector3f(ls, std::log(1e-7f), ls), Eigen::Vector4f(0.9f, 0.1f, 0.3f, 0.2f), 0)},
      {"needle", one_gaussian(center, Eigen::Vector3f(std::log(2.f), std::log(1e-6f), std::log(1e-6f)), Eigen::Vector4f(0.3f, 0.6f, 0.1f, 0.7f), 0)},
      {"opacity logit +50", one_gaussian(center, Eigen::Vector3f::Constant(ls), id, 50)},
      {"opacity logit -50", one_gaussian(center, Eigen::Vector3f::Constant(ls), id, -50)},
      {"huge log scale", one_gaussian(center, Eigen::Vector3f::Constant(80.f), id, 0)},
      {"infinite position", one_gaussian(Eigen::Vector3f(INFINITY, 0, 0), Eigen::Vector3f::Constant(ls), id, 0)},
  };
  for (const Case& cs : cases) expect_finite_pipeline(cs.g, c, cs.name);
  // Thousands of Gaussians in one tile, and empty tiles around them.
  GaussianSet<float> many = random_gaussians<float>(3000, 5, 0.02, 0.01, 0.1);
  expect_finite_pipeline(many, front_camera(96, 64), "3000 Gaussians in one tile");
  RasterState<float> st;
  rasterize_forward(many, RasterCamera<float>::from(front_camera(96, 64)), RasterSettings<float>{}, &st);
  int64_t max_list = 0, empty = 0;
  for (int t = 0; t < st.tiles_x * st.tiles_y; ++t) {
    max_list = std::max(max_list, st.tile_offset[t + 1] - st.tile_offset[t]);
    empty += st.tile_offset[t + 1] == st.tile_offset[t];
  }
  EXPECT_GE(max_list, 2000);
  EXPECT_GT(empty, 0);
  // No Gaussians at all, and a 1x1 image.
  expect_finite_pipeline(GaussianSet<float>{}, c, "no Gaussians");
  expect_finite_pipeline(random_gaussians<float>(50, 6), front_camera(1, 1), "1x1 image");
}

TEST(RasterizerTest, BackgroundShowsWhereNothingIsDrawn) {
  const Camera c = front_camera(20, 10);
  RasterState<float> st;
  RasterSettings<float> rs;
  rs.background = {0.25f, 0.5f, 1.0f};
  rasterize_forward(GaussianSet<float>{}, RasterCamera<float>::from(c), rs, &st);
  for (size_t p = 0; p < 200; ++p)
    for (int ch = 0; ch < 3; ++ch) ASSERT_EQ(st.image[p * 3 + ch], rs.background[ch]);
}

TEST(RasterizerTest, ResultsDoNotDependOnThreadCount) {
  const Camera c = front_camera(90, 70);
  const GaussianSet<float> g = random_gaussians<float>(2000, 8, 1.0, 0.05, 0.2);
  std::vector<float> target(90 * 70 * 3, 0.3f);
  auto run = [&](int threads, GaussianSet<float>* grad) {
    set_num_threads(threads);
    RasterState<float> st;
    const RasterCamera<float> cam = RasterCamera<float>::from(c);
    rasterize_forward(g, cam, RasterSettings<float>{}, &st);
    std::vector<float> v;
    photometric_loss<float>(st.image, target, nullptr, c.width, c.height, 0.2f, &v);
    rasterize_backward(g, cam, RasterSettings<float>{}, &st, v, grad);
    return st.image;
  };
  GaussianSet<float> g1, g2;
  const std::vector<float> a = run(1, &g1), b = run(2, &g2);
  set_num_threads(0);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * 4), 0);
  EXPECT_EQ(std::memcmp(g1.position.data(), g2.position.data(), g1.position.size() * 4), 0);
  EXPECT_EQ(std::memcmp(g1.sh.data(), g2.sh.data(), g1.sh.size() * 4), 0);
  EXPECT_EQ(std::memcmp(g1.rotation.data(), g2.rotation.data(), g1.rotation.size() * 4), 0);
}

// max_blend_weights against the per-pixel loop in double (test_scene.h): exactly in double (the same
// operations in the same order), and in float within what the float blend's rounding allows. Many
// Gaussians per pixel, so that transmittance, the 1/255 cut-off and stopped pixels all matter.
TEST(RasterizerTest, MaxBlendWeightsEqualPerPixelReference) {
  const Camera c = front_camera(70, 45);
  const GaussianSet<double> g = random_gaussians<double>(600, 31, 1.0, 0.1, 0.2);
  const std::vector<double> want = testing::reference_max_blend_weights(g, c);
  RasterState<double> st;
  rasterize_forward(g, RasterCamera<double>::from(c), RasterSettings<double>{}, &st);
  std::vector<double> got;
  max_blend_weights(st, &got);
  ASSERT_EQ(got.size(), want.size());
  int blended = 0, hidden = 0;
  for (size_t i = 0; i < g.size(); ++i) {
    EXPECT_NEAR(got[i], want[i], 1e-12) << "Gaussian " << i;
    blended += want[i] > 0;
    hidden += want[i] > 0 && want[i] < 0.01;
  }
  EXPECT_GT(blended, 300);
  EXPECT_GT(hidden, 20);  // Gaussians behind others: their weights are the transmittance's doing
  // Float: alpha and transmittance round at ~1e-7 relative; a Gaussian at the 1/255 cut-off may
  // flip, which moves its own weight by at most ~1/255 and those behind it by less.
  constexpr double kFloatTolerance = 5e-3;
  const GaussianSet<float> gf = g.cast<float>();
  RasterState<float> sf;
  rasterize_forward(gf, RasterCamera<float>::from(c), RasterSettings<float>{}, &sf);
  std::vector<float> got_f;
  max_blend_weights(sf, &got_f);
  for (size_t i = 0; i < g.size(); ++i) EXPECT_NEAR(got_f[i], want[i], kFloatTolerance) << "Gaussian " << i;
}

TEST(RasterizerTest, MaxBlendWeightsDoNotDependOnThreadCountOrOutputs) {
  const Camera c = front_camera(90, 70);
  const GaussianSet<float> g = random_gaussians<float>(2000, 8, 1.0, 0.05, 0.2);
  auto run = [&](int threads, RasterOutputs outputs) {
    set_num_threads(threads);
    RasterSettings<float> rs;
    rs.outputs = outputs;
    RasterState<float> st;
    rasterize_forward(g, RasterCamera<float>::from(c), rs, &st);
    std::vector<float> w;
    max_blend_weights(st, &w);
    return w;
  };
  const std::vector<float> a = run(1, RasterOutputs::kTraining), b = run(2, RasterOutputs::kTraining);
  const std::vector<float> d = run(2, RasterOutputs::kImage);
  set_num_threads(0);
  ASSERT_EQ(a.size(), g.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * 4), 0);
  EXPECT_EQ(std::memcmp(a.data(), d.data(), a.size() * 4), 0);
  EXPECT_GT(*std::max_element(a.begin(), a.end()), 0.5f);
}

// The 8-lane tile kernels (AVX2) give the bits of the 4-lane ones: image,
// transmittance, contributor counts and every gradient, on a scene with splats of all sizes, low
// opacities and a background (so every branch of the blend is taken). Widths the CPU cannot run
// are reported, not silently passed.
TEST(RasterizerTest, EveryKernelWidthGivesTheSameBits) {
  const Camera c = front_camera(93, 70);  // partial tiles on both edges
  GaussianSet<float> g = random_gaussians<float>(3000, 12, 1.0, 0.12, 0.2);
  for (size_t i = 0; i < g.size(); i += 7) g.opacity_logit[i] = -5.f;  // alpha near the 1/255 cut-off
  RasterSettings<float> rs;
  rs.background = {0.2f, 0.5f, 0.9f};
  std::vector<float> target(size_t(c.width) * c.height * 3);
  Rng rng(5, 0, 0);
  for (float& v : target) v = float(rng.uniform_double());
  const RasterCamera<float> cam = RasterCamera<float>::from(c);
  struct Out {
    RasterState<float> st;
    GaussianSet<float> grad;
    std::vector<float> ndc;
  };
  auto run = [&](int width, Out* out) {
    EXPECT_TRUE(internal::set_tile_kernel_width(width));
    rasterize_forward(g, cam, rs, &out->st);
    std::vector<float> v;
    photometric_loss<float>(out->st.image, target, nullptr, c.width, c.height, 0.2f, &v);
    rasterize_backward(g, cam, rs, &out->st, v, &out->grad, &out->ndc);
  };
  const int native = internal::tile_kernel_width();
  Out ref;
  run(4, &ref);
  auto same = [](const auto& a, const auto& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0;
  };
  int compared = 0;
  for (int width : {8}) {
    if (!internal::set_tile_kernel_width(width)) {
      std::printf("tile kernel width %d: not supported by this CPU, not compared\n", width);
      continue;
    }
    Out o;
    run(width, &o);
    ++compared;
    EXPECT_TRUE(same(ref.st.image, o.st.image)) << width;
    EXPECT_TRUE(same(ref.st.final_transmittance, o.st.final_transmittance)) << width;
    EXPECT_TRUE(same(ref.st.n_contrib, o.st.n_contrib)) << width;
    EXPECT_TRUE(same(ref.st.entry_grad, o.st.entry_grad)) << width;
    EXPECT_TRUE(same(ref.grad.position, o.grad.position)) << width;
    EXPECT_TRUE(same(ref.grad.log_scale, o.grad.log_scale)) << width;
    EXPECT_TRUE(same(ref.grad.rotation, o.grad.rotation)) << width;
    EXPECT_TRUE(same(ref.grad.opacity_logit, o.grad.opacity_logit)) << width;
    EXPECT_TRUE(same(ref.grad.sh, o.grad.sh)) << width;
    EXPECT_TRUE(same(ref.ndc, o.ndc)) << width;
  }
  EXPECT_TRUE(internal::set_tile_kernel_width(native));
  EXPECT_FALSE(internal::set_tile_kernel_width(3));
  EXPECT_FALSE(internal::set_tile_kernel_width(16));
  EXPECT_EQ(internal::tile_kernel_width(), native);
  std::printf("tile kernel widths compared with 4: %d (native %d)\n", compared, native);
}

// An image-only forward (RasterOutputs::kImage: renders of test views) matches the training forward's
// image up to rounding: its block power is in Horner form and at 8 lanes with FMA it is fused
// (raster_image_simd.cc). Tolerances: rounding alone moves a pixel by a few float ulps (measured max
// 4e-7 over six random scenes), so the mean stays under kMeanTolerance. Where rounding
// decides a cut-off differently, the pixel moves by more: at the 1/255 cut-off by at most alpha T
// <= 1/255 (the later entries' share scales by 1 - alpha the other way), at the transmittance stop by
// at most the transmittance T there, which is 1e-4 / (1 - alpha) <= 0.01 (alpha <= 0.99); one of each
// in a pixel gives kMaxTolerance. Such pixels are rare (3 of 180,000 values in the densest measured
// scene): at most kFlipFraction of the values differ by more than 1e-5. The
// image-only render is deterministic: the same bits with 1 and 2 threads. The backward refuses its
// state (next test).
TEST(RasterizerTest, ImageOnlyForwardMatchesTheTrainingForward) {
  constexpr double kMeanTolerance = 1e-6, kMaxTolerance = 0.01 + 1.0 / 255.0, kFlipFraction = 1e-3;
  const Camera c = front_camera(93, 70);  // partial tiles on both edges
  GaussianSet<float> g = random_gaussians<float>(3000, 12, 1.0, 0.12, 0.2);
  for (size_t i = 0; i < g.size(); i += 7) g.opacity_logit[i] = -5.f;  // alpha near the 1/255 cut-off
  for (size_t i = 3; i < g.size(); i += 11) g.opacity_logit[i] = 6.f;  // alpha clamped at 0.99
  const RasterCamera<float> cam = RasterCamera<float>::from(c);
  const int native = internal::tile_kernel_width();
  int compared = 0;
  for (int width : {4, 8}) {
    if (!internal::set_tile_kernel_width(width)) continue;
    for (int degree : {0, 3}) {
      RasterSettings<float> rs;
      rs.sh_degree = degree;
      rs.background = {0.2f, 0.5f, 0.9f};
      RasterState<float> training, image, image_1thread;
      set_num_threads(2);
      rasterize_forward(g, cam, rs, &training);
      rs.outputs = RasterOutputs::kImage;
      rasterize_forward(g, cam, rs, &image);
      set_num_threads(1);
      rasterize_forward(g, cam, rs, &image_1thread);
      set_num_threads(0);
      ASSERT_EQ(training.image.size(), image.image.size());
      double sum = 0, worst = 0;
      int64_t flipped = 0;
      for (size_t i = 0; i < image.image.size(); ++i) {
        const double d = std::abs(double(training.image[i]) - double(image.image[i]));
        sum += d;
        worst = std::max(worst, d);
        flipped += d > 1e-5;
      }
      const double n = double(image.image.size());
      EXPECT_LE(sum / n, kMeanTolerance) << width << " " << degree;
      EXPECT_LE(worst, kMaxTolerance) << width << " " << degree;
      EXPECT_LE(double(flipped) / n, kFlipFraction) << width << " " << degree;
      std::printf("image-only vs training forward, %d lanes, degree %d: mean %.2g, max %.2g, %lld of %.0f over 1e-5\n",
                  width, degree, sum / n, worst, static_cast<long long>(flipped), n);
      // Not vacuous: if the two ever become bit-identical again, compare them with memcmp instead.
      EXPECT_GT(sum, 0.0) << "the image-only arithmetic is expected to round differently";
      EXPECT_EQ(std::memcmp(image_1thread.image.data(), image.image.data(), n * sizeof(float)), 0)
          << width << " " << degree;
      EXPECT_EQ(image.outputs, RasterOutputs::kImage);
      EXPECT_EQ(training.outputs, RasterOutputs::kTraining);
      ++compared;
    }
  }
  EXPECT_TRUE(internal::set_tile_kernel_width(native));
  EXPECT_GE(compared, 2);
}

TEST(RasterizerTest, BackwardRefusesAnImageOnlyForward) {
  const Camera c = front_camera(40, 30);
  const GaussianSet<float> g = random_gaussians<float>(50, 3, 1.0, 0.12, 0.2);
  const RasterCamera<float> cam = RasterCamera<float>::from(c);
  RasterSettings<float> rs;
  rs.outputs = RasterOutputs::kImage;
  RasterState<float> st;
  rasterize_forward(g, cam, rs, &st);
  const std::vector<float> v(st.image.size(), 0.f);
  GaussianSet<float> grad;
  EXPECT_THROW(rasterize_backward(g, cam, rs, &st, v, &grad), InternalError);  // exit 3 in the CLI
}

// SimdPreprocessEqualsScalar on one camera.
void check_simd_preprocess(const Camera& c) {
  GaussianSet<float> g = random_gaussians<float>(2045, 21, 2.5, 0.1, 0.3);
  Rng rng(22, 0, 0);
  for (size_t i = 0; i < g.size(); i += 5) {
    switch (int(i / 5) % 8) {
      case 0: for (int k = 0; k < 4; ++k) g.rotation[i * 4 + k] = 0.f; break;
      case 1: for (int k = 0; k < 4; ++k) g.rotation[i * 4 + k] = 1e-40f; break;
      case 2: g.rotation[i * 4 + 1] = NAN; break;
      case 3: g.log_scale[i * 3 + int(rng.uniform(0, 2.99))] = float(rng.uniform(-20, 12)); break;
      case 4: g.position[i * 3] = INFINITY; break;
      case 5:  // at the camera center, and just in front of the near plane
        for (int k = 0; k < 3; ++k) g.position[i * 3 + k] = float(c.center_world()[k]);
        break;
      case 6: g.opacity_logit[i] = float(rng.uniform(-12, 12)); break;
      default: g.position[i * 3 + 1] = -3.79f; break;
    }
  }
  const RasterCamera<float> cam = RasterCamera<float>::from(c);
  const int native = internal::tile_kernel_width();
  auto same = [](const auto& a, const auto& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0;
  };
  int compared = 0;
  int64_t paths[3] = {0, 0, 0};
  for (int width : {4, 8}) {
    if (!internal::set_tile_kernel_width(width)) {
      std::printf("width %d: not supported by this CPU, not compared\n", width);
      continue;
    }
    for (int degree = 0; degree <= kMaxShDegree; ++degree) {
      RasterSettings<float> rs;
      rs.sh_degree = degree;
      RasterState<float> simd, scalar;
      rasterize_forward(g, cam, rs, &simd);  // sizes the state, runs preprocess_simd
      scalar = simd;
      // Poison the per-Gaussian outputs, so that the comparison sees what the scalar pass writes.
      std::fill(scalar.splat.begin(), scalar.splat.end(), -7.f);
      std::fill(scalar.scale.begin(), scalar.scale.end(), -7.f);
      std::fill(scalar.mean2d.begin(), scalar.mean2d.end(), -7.f);
      std::fill(scalar.cov2d.begin(), scalar.cov2d.end(), -7.f);
      std::fill(scalar.depth.begin(), scalar.depth.end(), -7.f);
      std::fill(scalar.clamped.begin(), scalar.clamped.end(), uint8_t(7));
      std::fill(scalar.rect.begin(), scalar.rect.end(), -7);
      std::fill(scalar.radius.begin(), scalar.radius.end(), -7);
      std::fill(scalar.tile_mask.begin(), scalar.tile_mask.end(), 7u);
      internal::preprocess_scalar(g, cam, rs, &scalar);
      EXPECT_TRUE(same(simd.radius, scalar.radius)) << width << " " << degree;
      EXPECT_TRUE(same(simd.rect, scalar.rect)) << width << " " << degree;
      EXPECT_TRUE(same(simd.tile_mask, scalar.tile_mask)) << width << " " << degree;
      int visible = 0;
      for (size_t i = 0; i < g.size(); ++i) {
        if (scalar.radius[i] == 0) continue;
        ++visible;
        auto at = [&](const auto& v, int k) { return std::vector<float>(v.begin() + i * k, v.begin() + (i + 1) * k); };
        ASSERT_TRUE(same(at(simd.splat, kSplatFloats), at(scalar.splat, kSplatFloats))) << i << " " << width;
        ASSERT_TRUE(same(at(simd.cov2d, 3), at(scalar.cov2d, 3))) << i << " " << width;
        ASSERT_TRUE(same(at(simd.mean2d, 2), at(scalar.mean2d, 2))) << i << " " << width;
        ASSERT_TRUE(same(at(simd.scale, 3), at(scalar.scale, 3))) << i << " " << width;
        ASSERT_TRUE(same(at(simd.depth, 1), at(scalar.depth, 1))) << i << " " << width;
        ASSERT_EQ(simd.clamped[i], scalar.clamped[i]) << i << " " << width;
      }
      EXPECT_GT(visible, 1000);
      EXPECT_LT(visible, int(g.size()));  // the culled cases are culled
      for (size_t i = 0; i < g.size(); ++i) {  // which tile-mask paths the scene took
        const int32_t* r = &scalar.rect[i * 4];
        const int w = r[2] - r[0], h = r[3] - r[1];
        ++paths[w * h > kMaskTiles ? 2 : (w > 1 && h > 1) ? 1 : 0];
      }
    }
    ++compared;
  }
  EXPECT_TRUE(internal::set_tile_kernel_width(native));
  EXPECT_GE(compared, 1);
  std::printf("%dx%d: rects empty or one tile high/wide %lld, masked %lld, over %d tiles %lld\n", c.width, c.height,
              (long long)paths[0], (long long)paths[1], kMaskTiles, (long long)paths[2]);
  EXPECT_GT(paths[1], 0);
}

// The float SIMD preprocessing (projection, covariance, colour, tiles) gives the scalar template's
// bits at every width the CPU runs: on random Gaussians of all sizes, every SH degree, Gaussians
// behind the camera, at its center, with zero, denormal and NaN quaternions, huge and tiny scales,
// infinite positions, and a count that leaves a partial block.
TEST(RasterizerTest, SimdPreprocessEqualsScalar) {
  for (const Camera& c : {front_camera(93, 70), front_camera(301, 203)})  // partial tiles; rects of > 64 tiles
    check_simd_preprocess(c);
}

}  // namespace
}  // namespace weathergs::reconstruction
