// gs-w-lite's appearance and visibility (reconstruction/in_the_wild.h): gradients against central
// finite differences of the loss the trainer minimises, the warm-up, the checkpoint state.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/rng.h"
#include "reconstruction/in_the_wild.h"
#include "reconstruction/loss.h"

namespace weathergs::reconstruction {
namespace {

constexpr int kW = 20, kH = 14;

std::vector<TrainView> views(int n) {
  std::vector<TrainView> v(static_cast<size_t>(n));
  for (TrainView& t : v) {
    t.camera.width = kW;
    t.camera.height = kH;
  }
  return v;
}

std::vector<float> random_image(uint64_t seed) {
  Rng rng(seed, 0, 0);
  std::vector<float> img(size_t(kW) * kH * 3);
  for (float& x : img) x = rng.uniform();
  return img;
}

// The trainer's loss: photometric(M (A c + b), M t) + visibility_weight mean((1 - M)^2).
double total_loss(InTheWild& w, int it, const std::vector<float>& c, const std::vector<float>& t, double lambda) {
  std::vector<float> ro, to;
  w.forward(0, it, c, t, &ro, &to);
  const LossValue<float> lv = photometric_loss<float>(ro, to, nullptr, kW, kH, float(lambda), nullptr);
  return double(lv.loss) + w.regulariser(0, it);
}

void check_gradients(double lambda, int it, bool check_logits) {
  InTheWildOptions o;
  o.from = 10;
  o.lambda_dssim = lambda;
  o.cell_px = 4;
  InTheWild w(views(2), o);
  Rng rng(9, 0, 0);
  for (float& a : w.affine(0)) a += rng.uniform(-0.2f, 0.2f);
  for (float& l : w.logits(0)) l = rng.uniform(-1.f, 2.f);
  std::vector<float> c = random_image(1);
  const std::vector<float> t = random_image(2);
  std::vector<float> ro, to, v;
  w.forward(0, it, c, t, &ro, &to);
  photometric_loss<float>(ro, to, nullptr, kW, kH, float(lambda), &v);
  w.backward(0, it, c, t, &v);
  const std::vector<float> ga = w.affine_grad(), gl = w.logits_grad();
  // Central differences of a float32 loss of ~0.3 with h = 1e-3: rounding ~3e-8 / 2e-3 ~ 2e-5;
  // truncation O(h^2). Gradients here are 1e-4 .. 1e-1.
  constexpr float kH = 1e-3f;
  constexpr double kAbs = 1e-4, kRel = 2e-2;
  // The central difference of the loss in one value, checked against its analytic gradient.
  auto check = [&](float& x, float analytic, const char* what, size_t k) {
    const float x0 = x;
    x = x0 + kH;
    const double lp = total_loss(w, it, c, t, lambda);
    x = x0 - kH;
    const double lm = total_loss(w, it, c, t, lambda);
    x = x0;
    const double fd = (lp - lm) / (2 * kH);
    EXPECT_NEAR(analytic, fd, kAbs + kRel * std::abs(fd)) << what << " " << k;
  };
  for (size_t k = 0; k < 12; ++k) check(w.affine(0)[k], ga[k], "affine", k);
  // d loss / d render (what the Gaussians receive), on a few pixels and channels.
  for (size_t k = 0; k < c.size(); k += 37) check(c[k], v[k], "render value", k);
  if (!check_logits) return;
  for (size_t k = 0; k < gl.size(); k += 3) check(w.logits(0)[k], gl[k], "logit", k);
}

TEST(InTheWildTest, AppearanceGradientMatchesFiniteDifferences) {
  check_gradients(0.2, 5, false);   // before the warm-up ends: M = 1
  check_gradients(0.2, 50, false);  // with the map: the full loss (L1 + D-SSIM) through the render
}

TEST(InTheWildTest, VisibilityGradientMatchesFiniteDifferencesOfL1AndRegulariser) {
  // The map learns from the L1 term and the regulariser (the D-SSIM term is not differentiated with
  // respect to M, by design): exact with lambda_dssim = 0.
  check_gradients(0.0, 50, true);
}

TEST(InTheWildTest, IdentityBeforeTheWarmUpAndCheckpointState) {
  InTheWildOptions o;
  o.from = 10;
  InTheWild w(views(3), o);
  const std::vector<float> c = random_image(3), t = random_image(4);
  std::vector<float> ro, to;
  w.forward(1, 5, c, t, &ro, &to);
  EXPECT_EQ(ro, c);
  EXPECT_EQ(to, t);
  EXPECT_EQ(w.regulariser(1, 5), 0.0);
  // A few steps change the state; restoring it into a fresh object gives the same next forward.
  for (int it = 1; it < 30; ++it) {
    std::vector<float> v(c.size(), 1e-3f);
    w.forward(1, it, c, t, &ro, &to);
    w.backward_and_step(1, it, c, t, &v);
  }
  InTheWild r(views(3), o);
  r.restore(w.state());
  std::vector<float> a, b;
  w.forward(1, 40, c, t, &a, &to);
  r.forward(1, 40, c, t, &b, &to);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_THROW(r.restore(std::vector<float>(3)), InputError);
}

}  // namespace
}  // namespace weathergs::reconstruction
