// Every backward step against central finite differences in double precision.
#include <gtest/gtest.h>

#include <functional>

#include "core/rng.h"
#include "reconstruction/gaussian_math.h"
#include "reconstruction/loss.h"
#include "reconstruction/rasterizer.h"
#include "tests/reconstruction/test_scene.h"

namespace weathergs::reconstruction {
namespace {

using testing::look_at_camera;
using testing::random_gaussians;

// Central differences in double: truncation error ~ h^2 * f''' ~ 1e-12 and rounding error
// ~ eps * |f| / h ~ 1e-10 for |f| ~ 1, so 1e-6 relative plus 1e-8 absolute is far above the noise
// and far below any real mistake (a wrong term changes a gradient by O(1) relatively).
constexpr double kFdStep = 1e-6;
constexpr double kFdRelTol = 1e-6;
constexpr double kFdAbsTol = 1e-8;

double central_difference(const std::function<double()>& f, double* x, double h = kFdStep) {
  const double x0 = *x;
  *x = x0 + h;
  const double fp = f();
  *x = x0 - h;
  const double fm = f();
  *x = x0;
  return (fp - fm) / (2 * h);
}

void expect_close(double analytic, double numeric, const std::string& what) {
  EXPECT_NEAR(analytic, numeric, kFdAbsTol + kFdRelTol * (std::abs(analytic) + std::abs(numeric))) << what;
}

Mat3<double> random_mat3(uint64_t seed) {
  Rng rng(seed, 2, 0);
  Mat3<double> m;
  for (int i = 0; i < 9; ++i) m(i / 3, i % 3) = rng.normal();
  return m;
}

RasterCamera<double> test_camera(int w = 40, int h = 30) {
  return RasterCamera<double>::from(look_at_camera("c", w, h, 45.0, Eigen::Vector3d(0.3, -3.5, 1.0)));
}

TEST(GradientTest, QuaternionToRotation) {
  const Mat3<double> w = random_mat3(1);
  Vec4<double> q(0.7, -0.3, 0.5, 0.2);
  auto f = [&] { return (quat_to_rotmat(q).array() * w.array()).sum(); };
  const Vec4<double> v = quat_to_rotmat_vjp(q, w);
  for (int k = 0; k < 4; ++k) expect_close(v[k], central_difference(f, &q[k]), "q" + std::to_string(k));
  // The result is a rotation.
  const Mat3<double> r = quat_to_rotmat(q);
  EXPECT_NEAR((r * r.transpose() - Mat3<double>::Identity()).norm(), 0, 1e-12);
  EXPECT_NEAR(r.determinant(), 1, 1e-12);
}

TEST(GradientTest, CovarianceFromScaleAndRotation) {
  Mat3<double> w = random_mat3(2);
  w = (w + w.transpose()).eval();  // a symmetric weight: the loss sees a symmetric matrix
  Vec3<double> ls(std::log(0.3), std::log(0.05), std::log(1.2));
  Vec4<double> q(0.2, 0.9, -0.4, 0.3);
  auto f = [&] { return (covariance_3d(ls, q).array() * w.array()).sum(); };
  Vec3<double> v_ls = Vec3<double>::Zero();
  Vec4<double> v_q = Vec4<double>::Zero();
  covariance_3d_vjp(ls, q, w, &v_ls, &v_q);
  for (int k = 0; k < 3; ++k) expect_close(v_ls[k], central_difference(f, &ls[k]), "log_scale" + std::to_string(k));
  for (int k = 0; k < 4; ++k) expect_close(v_q[k], central_difference(f, &q[k]), "q" + std::to_string(k));
}

TEST(GradientTest, ProjectionMeanAndCovariance) {
  const RasterCamera<double> cam = test_camera();
  Mat3<double> sigma = random_mat3(3);
  sigma = (sigma * sigma.transpose() * 0.01).eval();
  Mat2<double> w_cov;
  w_cov << 0.3, -0.7, -0.7, 1.1;
  const Vec2<double> w_mean(0.4, -0.9);
  // Inside the frustum, and outside it so that the Jacobian clamp is active in x and in y.
  for (Vec3<double> p : {Vec3<double>(0.2, 0.1, -0.3), Vec3<double>(4.0, 0.5, 0.2), Vec3<double>(0.1, 0.4, 4.0)}) {
    auto f = [&] {
      Projection<double> pr = project_gaussian(p, sigma, cam);
      return (pr.cov.array() * w_cov.array()).sum() + pr.mean.dot(w_mean);
    };
    Vec3<double> v_p = Vec3<double>::Zero();
    Mat3<double> v_sigma = Mat3<double>::Zero();
    project_gaussian_vjp(p, sigma, cam, w_mean, w_cov, &v_p, &v_sigma);
    for (int k = 0; k < 3; ++k) expect_close(v_p[k], central_difference(f, &p[k]), "p" + std::to_string(k));
    // Sigma is symmetric: perturb (i, j) and (j, i) together and compare with the sum of both entries.
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j) {
        auto fs = [&] { return f(); };
        double base = sigma(i, j);
        auto set = [&](double v) { sigma(i, j) = v; sigma(j, i) = v; };
        set(base + kFdStep);
        double fp = fs();
        set(base - kFdStep);
        double fm = fs();
        set(base);
        const double analytic = i == j ? v_sigma(i, i) : v_sigma(i, j) + v_sigma(j, i);
        expect_close(analytic, (fp - fm) / (2 * kFdStep), "sigma");
      }
  }
}

TEST(GradientTest, ConicFromCovariance) {
  Mat2<double> cov;
  cov << 2.0, 0.6, 0.6, 1.3;
  const Vec3<double> w(0.5, -1.5, 0.8);
  auto f = [&] {
    const double det = cov(0, 0) * cov(1, 1) - cov(0, 1) * cov(1, 0);
    return w[0] * cov(1, 1) / det - w[1] * cov(0, 1) / det + w[2] * cov(0, 0) / det;
  };
  const Mat2<double> v = inverse_2x2_vjp(cov, w);
  double a = cov(0, 0), c = cov(1, 1);
  expect_close(v(0, 0), central_difference(f, &cov(0, 0)), "a");
  expect_close(v(1, 1), central_difference(f, &cov(1, 1)), "c");
  (void)a; (void)c;
  // Off-diagonal: the covariance's b appears twice; perturb both.
  const double b = cov(0, 1);
  cov(0, 1) = cov(1, 0) = b + kFdStep;
  double fp = f();
  cov(0, 1) = cov(1, 0) = b - kFdStep;
  double fm = f();
  expect_close(2 * v(0, 1), (fp - fm) / (2 * kFdStep), "b");
}

TEST(GradientTest, ShColour) {
  const Vec3<double> cam(0.5, -2, 1);
  Vec3<double> p(0.3, 0.2, -0.4);
  std::vector<double> sh(kShFloats);
  Rng rng(4, 0, 0);
  for (double& v : sh) v = 0.1 * rng.normal();
  sh[0] = sh[1] = sh[2] = 1.5;  // keep every channel above the clamp
  const Vec3<double> w(0.3, -0.8, 1.1);
  for (int degree = 0; degree <= 3; ++degree) {
    auto f = [&] {
      double len;
      bool cl[3];
      return sh_to_color(degree, sh.data(), view_direction(p, cam, &len), cl).dot(w);
    };
    double len;
    bool cl[3];
    sh_to_color(degree, sh.data(), view_direction(p, cam, &len), cl);
    ASSERT_FALSE(cl[0] || cl[1] || cl[2]);
    std::vector<double> v_sh(kShFloats, 0.0);
    Vec3<double> v_p = Vec3<double>::Zero();
    sh_to_color_vjp(degree, sh.data(), p, cam, w, cl, v_sh.data(), &v_p);
    for (int k = 0; k < kShFloats; ++k)
      expect_close(v_sh[k], central_difference(f, &sh[k]), "sh" + std::to_string(k) + " degree " + std::to_string(degree));
    for (int k = 0; k < 3; ++k)
      expect_close(v_p[k], central_difference(f, &p[k]), "p" + std::to_string(k) + " degree " + std::to_string(degree));
  }
}

// The whole rasterizer (projection, covariance, SH, binning and blending) against finite differences
// of a weighted sum of the image, with a non-black background.
TEST(GradientTest, RasterizerEndToEnd) {
  const RasterCamera<double> cam = test_camera(40, 30);
  GaussianSet<double> g = random_gaussians<double>(25, 11, 0.7, 0.15, 0.2);
  RasterSettings<double> rs;
  rs.background = {0.2, 0.5, 0.9};
  std::vector<double> w(40 * 30 * 3);
  Rng rng(5, 0, 0);
  for (double& v : w) v = rng.uniform_double() - 0.3;
  RasterState<double> st;
  rasterize_forward(g, cam, rs, &st);
  // The sum is taken relative to the unperturbed image: the difference quotient then does not
  // subtract two large sums (whose rounding, ~1e-12, divided by 2h would swamp the comparison).
  const std::vector<double> base = st.image;
  auto f = [&] {
    rasterize_forward(g, cam, rs, &st);
    double s = 0;
    for (size_t i = 0; i < w.size(); ++i) s += w[i] * (st.image[i] - base[i]);
    return s;
  };
  f();
  GaussianSet<double> grad;
  rasterize_backward(g, cam, rs, &st, w, &grad);
  int visible = 0;
  for (size_t i = 0; i < g.size(); ++i) visible += st.radius[i] > 0;
  EXPECT_GE(visible, 20);
  for (size_t i = 0; i < g.size(); i += 3) {
    const std::string id = " of Gaussian " + std::to_string(i);
    for (int k = 0; k < 3; ++k) {
      expect_close(grad.position[i * 3 + k], central_difference(f, &g.position[i * 3 + k]), "position" + id);
      expect_close(grad.log_scale[i * 3 + k], central_difference(f, &g.log_scale[i * 3 + k]), "log_scale" + id);
    }
    for (int k = 0; k < 4; ++k)
      expect_close(grad.rotation[i * 4 + k], central_difference(f, &g.rotation[i * 4 + k]), "rotation" + id);
    expect_close(grad.opacity_logit[i], central_difference(f, &g.opacity_logit[i]), "opacity" + id);
    for (int k = 0; k < kShFloats; k += 5)
      expect_close(grad.sh[i * kShFloats + k], central_difference(f, &g.sh[i * kShFloats + k]), "sh" + id);
  }
}

// Loss: masked L1 + SSIM against finite differences on the rendered pixels, with and without a mask.
TEST(GradientTest, MaskedL1SsimLoss) {
  const int w = 23, h = 17;
  std::vector<double> render(w * h * 3), target(w * h * 3);
  Rng rng(6, 0, 0);
  for (size_t i = 0; i < render.size(); ++i) {
    target[i] = rng.uniform_double();
    render[i] = std::clamp(target[i] + 0.3 * (rng.uniform_double() - 0.5), 0.0, 1.0);
  }
  std::vector<uint8_t> mask(w * h, 0);
  for (int y = 4; y < 11; ++y)
    for (int x = 6; x < 15; ++x) mask[y * w + x] = 1;
  const std::vector<const std::vector<uint8_t>*> masks = {nullptr, &mask};
  for (const std::vector<uint8_t>* m : masks) {
    std::vector<double> v;
    const LossValue<double> lv = photometric_loss<double>(render, target, m, w, h, kLambdaDssim, &v);
    EXPECT_GT(lv.loss, 0);
    auto f = [&] { return double(photometric_loss<double>(render, target, m, w, h, kLambdaDssim, nullptr).loss); };
    for (size_t i = 0; i < render.size(); i += 7) {
      // Skip points where |render - target| is within the step (L1 kink).
      if (std::abs(render[i] - target[i]) < 10 * kFdStep) continue;
      expect_close(v[i], central_difference(f, &render[i]), "pixel " + std::to_string(i));
    }
    if (m) {
      for (int p = 0; p < w * h; ++p) {
        if (!mask[p]) continue;
        for (int c = 0; c < 3; ++c) EXPECT_EQ(v[p * 3 + c], 0.0) << "masked pixel " << p;
      }
    }
  }

  // kReference (the WeatherGS release's normalisation): the same as the unmasked loss against the
  // target with its masked pixels replaced by the render (held constant), value and gradient, and
  // that unmasked loss is checked against finite differences above.
  std::vector<double> composited = target;
  for (int p = 0; p < w * h; ++p)
    if (mask[p])
      for (int c = 0; c < 3; ++c) composited[p * 3 + c] = render[p * 3 + c];
  std::vector<double> v_ref, v_plain;
  const LossValue<double> ref =
      photometric_loss<double>(render, target, &mask, w, h, kLambdaDssim, &v_ref, MaskNormalization::kReference);
  const LossValue<double> plain = photometric_loss<double>(render, composited, nullptr, w, h, kLambdaDssim, &v_plain);
  EXPECT_NEAR(ref.loss, plain.loss, 1e-12);
  ASSERT_EQ(v_ref.size(), v_plain.size());
  double masked_gradient = 0;
  for (size_t i = 0; i < v_ref.size(); ++i) {
    EXPECT_NEAR(v_ref[i], v_plain[i], 1e-12) << i;
    if (mask[i / 3]) masked_gradient += std::abs(v_ref[i]);
  }
  EXPECT_GT(masked_gradient, 0.0) << "masked pixels take part in their neighbours' SSIM windows";
  // Averaged over all pixels: a lower loss than the valid-pixel normalisation of the same residuals.
  const LossValue<double> valid = photometric_loss<double>(render, target, &mask, w, h, kLambdaDssim, nullptr);
  EXPECT_LT(ref.l1, valid.l1);
  EXPECT_EQ(std::string(to_string(MaskNormalization::kReference)), "reference");
}

}  // namespace
}  // namespace weathergs::reconstruction
