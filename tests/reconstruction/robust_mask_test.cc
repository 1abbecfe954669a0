// The RobustFilter rule (reconstruction/robust_mask.h) against hand-computed cases: the running
// percentile threshold, the 3x3 neighbourhood rule, the annealed warm-up and determinism.
#include <gtest/gtest.h>

#include <cmath>

#include "reconstruction/robust_mask.h"

namespace weathergs::reconstruction {
namespace {

// An H x W x 3 pair whose per-pixel error (mean over channels) is `err[i]`.
void pair_with_errors(const std::vector<float>& err, std::vector<float>* render, std::vector<float>* target) {
  render->assign(err.size() * 3, 0.25f);
  target->assign(err.size() * 3, 0.25f);
  for (size_t i = 0; i < err.size(); ++i)
    for (int c = 0; c < 3; ++c) (*render)[i * 3 + c] = 0.25f + err[i];
}

TEST(RobustMaskTest, ThresholdIsTheRunningSeventiethPercentile) {
  RobustMask m;
  EXPECT_EQ(m.threshold(), 1.0);  // before any update every pixel is an inlier
  // 100 pixels with errors 0.00, 0.01, ..., 0.99: the 70th percentile is the bin of 0.69.
  std::vector<float> err(100);
  for (int i = 0; i < 100; ++i) err[size_t(i)] = float(i) / 100.f;
  std::vector<float> r, t;
  pair_with_errors(err, &r, &t);
  m.update(robust_pixel_errors(r, t));
  // Bins of width 1e-4; 0.69 lands in bin 6899 or 6900 depending on float rounding.
  EXPECT_NEAR(m.threshold(), 0.69, 2e-4);
  // A later, uniformly larger error pulls the running threshold up only partly (decay 0.95).
  for (float& e : err) e = std::min(1.f, e + 0.2f);
  pair_with_errors(err, &r, &t);
  m.update(robust_pixel_errors(r, t));
  EXPECT_GT(m.threshold(), 0.69);
  EXPECT_LT(m.threshold(), 0.89 + 2e-4);
  // Out-of-range errors (a render above 1) are not counted, as in torch.histogram.
  RobustMask only_big;
  pair_with_errors(std::vector<float>(9, 2.f), &r, &t);
  only_big.update(robust_pixel_errors(r, t));
  EXPECT_EQ(only_big.threshold(), 1.0);
}

TEST(RobustMaskTest, NeighbourhoodRuleAndWarmUp) {
  RobustMask m;
  // Threshold 0.5 from a histogram that is half zeros, half ones.
  std::vector<float> half(100, 0.f);
  for (int i = 50; i < 100; ++i) half[size_t(i)] = 1.f;
  std::vector<float> r, t;
  pair_with_errors(half, &r, &t);
  m.update(robust_pixel_errors(r, t));
  ASSERT_NEAR(m.threshold(), 1.0 - 1e-4, 1e-9);  // 70% of the mass is reached in the last bin
  m.restore(std::vector<double>(10000, 0.0), 0.5);
  // 7x7 image: a single outlier at (1,1) and a 3x3 outlier block centred at (5,5) (clipped).
  const int w = 7, h = 7;
  std::vector<float> err(size_t(w * h), 0.f);
  err[1 * w + 1] = 0.9f;
  for (int y = 4; y < 7; ++y)
    for (int x = 4; x < 7; ++x) err[size_t(y * w + x)] = 0.9f;
  pair_with_errors(err, &r, &t);
  const int late = 100000;  // warm-up over: alpha = exp(-3e-3 * 66666) ~ 1e-87
  EXPECT_LT(m.keep_probability(late), 1e-80);
  std::vector<uint8_t> invalid(size_t(w * h), 0);
  m.exclude(robust_pixel_errors(r, t), w, h, late, 7, &invalid);
  EXPECT_EQ(invalid[1 * w + 1], 0) << "a lone outlier among inliers is kept (8 of 9 neighbours are inliers)";
  EXPECT_EQ(invalid[5 * w + 5], 1) << "the centre of an outlier block is excluded";
  EXPECT_EQ(invalid[6 * w + 6], 1) << "zero padding: the corner has 4 outliers and 5 padded zeros";
  EXPECT_EQ(invalid[4 * w + 4], 0) << "an outlier with 5 inliers among its 9 (more than half) is kept";
  // Warm-up: alpha = exp(beta floor((1 + step) / 1.5)) with step = iteration - 1: 1 at the first
  // iteration, exp(-3e-3) ~ 0.997 at the second: early on almost every excluded pixel is kept.
  EXPECT_EQ(m.keep_probability(1), 1.0);
  EXPECT_NEAR(m.keep_probability(2), std::exp(-3e-3), 1e-12);
  EXPECT_NEAR(m.keep_probability(1000), std::exp(-3e-3 * 666), 1e-12);
  // Statistically: a large all-outlier image keeps a fraction alpha of its pixels.
  const int big = 200;
  std::vector<float> all_out(size_t(big * big), 0.9f);
  pair_with_errors(all_out, &r, &t);
  const int it = 500;
  std::vector<uint8_t> a(size_t(big * big), 0), b(size_t(big * big), 0);
  m.exclude(robust_pixel_errors(r, t), big, big, it, 7, &a);
  m.exclude(robust_pixel_errors(r, t), big, big, it, 7, &b);
  EXPECT_EQ(a, b) << "the draws are keyed on (seed, iteration, row)";
  double kept = 0;
  for (uint8_t v : a) kept += v ? 0 : 1;
  kept /= double(big * big);
  // 40000 Bernoulli draws: standard error sqrt(p(1-p)/n) < 0.0025; 5 sigma.
  EXPECT_NEAR(kept, m.keep_probability(it), 0.0125);
  // Pixels already excluded by the view's own mask stay excluded.
  std::vector<uint8_t> pre(size_t(w * h), 1);
  pair_with_errors(std::vector<float>(size_t(w * h), 0.f), &r, &t);
  m.exclude(robust_pixel_errors(r, t), w, h, late, 7, &pre);
  for (uint8_t v : pre) EXPECT_EQ(v, 1);
}

}  // namespace
}  // namespace weathergs::reconstruction
