#include "reconstruction/robust_mask.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/rng.h"

namespace weathergs::reconstruction {

namespace {
constexpr uint64_t kStreamRobust = 0x726f62757374ull;  // "robust": the warm-up's Bernoulli draws
}  // namespace

std::vector<float> robust_pixel_errors(const std::vector<float>& render, const std::vector<float>& target) {
  WGS_CHECK_EQ(render.size(), target.size());
  WGS_CHECK_EQ(render.size() % 3, size_t(0));
  const size_t n = render.size() / 3;
  std::vector<float> e(n);
  for (size_t i = 0; i < n; ++i)
    e[i] = (std::abs(render[i * 3] - target[i * 3]) + std::abs(render[i * 3 + 1] - target[i * 3 + 1]) +
            std::abs(render[i * 3 + 2] - target[i * 3 + 2])) / 3.f;
  return e;
}

RobustMask::RobustMask(RobustMaskOptions options) : options_(options), histogram_(size_t(options.bins), 0.0) {
  WGS_CHECK(options_.bins > 0);
  WGS_CHECK(options_.percentile > 0 && options_.percentile <= 1);
}

double RobustMask::keep_probability(int iteration) const {
  const int step = iteration - 1;  // the reference's 0-based step
  return std::clamp(std::exp(options_.schedule_beta * std::floor((1.0 + step) / 1.5)), 0.0, 1.0);
}

void RobustMask::exclude(const std::vector<float>& e, int width, int height, int iteration, uint64_t seed,
                         std::vector<uint8_t>* invalid) const {
  const size_t n = size_t(width) * height;
  WGS_CHECK_EQ(invalid->size(), n);
  WGS_CHECK_EQ(e.size(), n);
  std::vector<uint8_t> inlier(n);
  for (size_t i = 0; i < n; ++i) inlier[i] = e[i] < threshold_ ? 1 : 0;
  const double alpha = keep_probability(iteration);
  for (int y = 0; y < height; ++y) {
    Rng rng(seed, kStreamRobust ^ (uint64_t(iteration) << 20), uint64_t(y));
    for (int x = 0; x < width; ++x) {
      const size_t i = size_t(y) * width + x;
      // 3x3 box mean of the inlier indicator with zero padding (the reference's conv2d), > 0.5.
      int count = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int yy = y + dy, xx = x + dx;
          if (yy >= 0 && yy < height && xx >= 0 && xx < width) count += inlier[size_t(yy) * width + xx];
        }
      const bool keep = inlier[i] || count * 2 > 9;
      // Always draw, so that the stream does not depend on the mask.
      const bool warm = rng.uniform() < alpha;
      if (!keep && !warm) (*invalid)[i] = 1;
    }
  }
}

void RobustMask::update(const std::vector<float>& e) {
  const int bins = options_.bins;
  for (double& h : histogram_) h *= options_.histogram_decay;
  for (float v : e) {
    // torch.histogram over [0, 1]: values outside are not counted; 1.0 falls in the last bin.
    if (!(v >= 0.f && v <= 1.f)) continue;
    histogram_[std::min(bins - 1, int(double(v) * bins))] += 1.0;
  }
  double total = 0;
  for (double h : histogram_) total += h;
  if (!(total > 0)) return;
  const double target_mass = total * options_.percentile;
  double cumulative = 0;
  for (int k = 0; k < bins; ++k) {
    cumulative += histogram_[size_t(k)];
    if (cumulative >= target_mass) {
      threshold_ = double(k) / bins;
      return;
    }
  }
  threshold_ = 1.0;
}

void RobustMask::restore(std::vector<double> histogram, double threshold) {
  WGS_CHECK_EQ(histogram.size(), size_t(options_.bins));
  histogram_ = std::move(histogram);
  threshold_ = threshold;
}

}  // namespace weathergs::reconstruction
