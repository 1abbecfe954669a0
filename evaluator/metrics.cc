#include "evaluator/metrics.h"

#include <cmath>
#include <limits>
#include <vector>

#include "core/parallel.h"

namespace weathergs::evaluator {

void require_comparable(const Image& a, const Image& b, const Image* mask, const std::string& where) {
  if (a.empty() || b.empty()) throw InputError(where, "empty image");
  if (a.width != b.width || a.height != b.height)
    throw InputError(where, "size mismatch: " + std::to_string(a.width) + "x" + std::to_string(a.height) +
                                " vs " + std::to_string(b.width) + "x" + std::to_string(b.height));
  if (a.channels != b.channels)
    throw InputError(where, "channel count mismatch: " + std::to_string(a.channels) + " vs " +
                                std::to_string(b.channels));
  if (mask && (mask->width != a.width || mask->height != a.height || mask->channels != 1))
    throw InputError(where, "mask is " + mask->to_string() + ", expected " + std::to_string(a.width) + "x" +
                                std::to_string(a.height) + "x1");
}

double mse(const Image& a, const Image& b, const Image* mask) {
  require_comparable(a, b, mask, "mse");
  // Per-row partial sums, added in row order: independent of the thread count.
  std::vector<double> row_sum(size_t(a.height), 0.0);
  std::vector<int64_t> row_count(size_t(a.height), 0);
  parallel_for(0, a.height, [&](int64_t y) {
    double s = 0;
    int64_t n = 0;
    for (int x = 0; x < a.width; ++x) {
      if (mask && mask->at(x, int(y)) >= 0.5f) continue;
      for (int c = 0; c < a.channels; ++c) {
        double d = double(a.at(x, int(y), c)) - double(b.at(x, int(y), c));
        s += d * d;
      }
      n += a.channels;
    }
    row_sum[size_t(y)] = s;
    row_count[size_t(y)] = n;
  }, 8);
  double s = 0;
  int64_t n = 0;
  for (int y = 0; y < a.height; ++y) { s += row_sum[size_t(y)]; n += row_count[size_t(y)]; }
  if (n == 0) throw InputError("mask", "the mask excludes every pixel: nothing left to score");
  return s / double(n);
}

double psnr(const Image& a, const Image& b, const Image* mask) {
  double m = mse(a, b, mask);
  if (m == 0) return std::numeric_limits<double>::infinity();
  return 10.0 * std::log10(1.0 / m);
}

void SsimOptions::validate() const {
  WGS_CHECK(sigma > 0 && radius >= 1 && k1 > 0 && k2 > 0 && data_range > 0);
}

std::string SsimOptions::protocol_name() const {
  char buf[96];
  std::snprintf(buf, sizeof buf, "gaussian%d_sigma%g_%s", 2 * radius + 1, sigma,
                padding == SsimPadding::kValid ? "valid" : "same");
  return buf;
}

namespace {

// SSIM statistics of one channel. The image is scored in double so that the E[x^2] - E[x]^2
// variances do not lose the digits the scikit-image comparison (1e-5) needs.
struct ChannelSsim {
  double sum = 0;
  int64_t count = 0;
};

ChannelSsim ssim_channel(const Image& a, const Image& b, int c, const SsimOptions& o, const Image* mask) {
  const int w = a.width, h = a.height, r = o.radius, taps = 2 * r + 1;
  std::vector<double> g(static_cast<size_t>(taps));
  double gs = 0;
  for (int i = -r; i <= r; ++i) gs += g[size_t(i + r)] = std::exp(-0.5 * i * i / (o.sigma * o.sigma));
  for (double& v : g) v /= gs;
  const double c1 = (o.k1 * o.data_range) * (o.k1 * o.data_range);
  const double c2 = (o.k2 * o.data_range) * (o.k2 * o.data_range);
  const bool valid = o.padding == SsimPadding::kValid;
  // Output window centres: valid -> [r, w - r) x [r, h - r); same -> the whole image.
  const int x0 = valid ? r : 0, x1 = valid ? w - r : w;
  const int y0 = valid ? r : 0, y1 = valid ? h - r : h;
  const int ow = x1 - x0, oh = y1 - y0;
  // Input row i of the padded row buffer is image column i - pad (zeros outside: "same" padding).
  const int pad = valid ? 0 : r;
  const size_t plane = size_t(h) * size_t(ow);

  // Horizontal pass: five planes (x, y, xx, yy, xy), structure of arrays, so that both passes are
  // contiguous multiply-adds the compiler vectorizes.
  std::vector<double> hp(plane * 5);
  parallel_for(0, h, [&](int64_t yy) {
    const int y = int(yy);
    const size_t n = size_t(w + 2 * pad);
    std::vector<double> in(n * 5, 0.0);
    double *ix = in.data(), *iy = ix + n, *ixx = iy + n, *iyy = ixx + n, *ixy = iyy + n;
    for (int x = 0; x < w; ++x) {
      const double va = a.at(x, y, c), vb = b.at(x, y, c);
      const size_t i = size_t(x + pad);
      ix[i] = va; iy[i] = vb; ixx[i] = va * va; iyy[i] = vb * vb; ixy[i] = va * vb;
    }
    for (int q = 0; q < 5; ++q) {
      const double* src = in.data() + size_t(q) * n;
      double* dst = &hp[size_t(q) * plane + size_t(y) * size_t(ow)];
      // Output column ox is centred on padded index ox + r (valid: image column x0 + ox = ox + r).
      for (int ox = 0; ox < ow; ++ox) dst[ox] = 0;
      for (int k = 0; k < taps; ++k) {
        const double wk = g[size_t(k)];
        const double* s = src + k;
        for (int ox = 0; ox < ow; ++ox) dst[ox] += wk * s[ox];
      }
    }
  }, 4);

  // Vertical pass and the SSIM formula, one partial sum per output row (reduced in row order).
  std::vector<double> row_sum(size_t(oh), 0.0);
  std::vector<int64_t> row_count(size_t(oh), 0);
  parallel_for(0, oh, [&](int64_t oyy) {
    const int cy = y0 + int(oyy);
    std::vector<double> m(size_t(ow) * 5, 0.0);
    for (int q = 0; q < 5; ++q) {
      double* acc = &m[size_t(q) * size_t(ow)];
      for (int k = -r; k <= r; ++k) {
        const int y = cy + k;
        if (y < 0 || y >= h) continue;  // zero padding (only reachable in "same")
        const double wk = g[size_t(k + r)];
        const double* src = &hp[size_t(q) * plane + size_t(y) * size_t(ow)];
        for (int ox = 0; ox < ow; ++ox) acc[ox] += wk * src[ox];
      }
    }
    const double *mx = m.data(), *my = mx + ow, *mxx = my + ow, *myy = mxx + ow, *mxy = myy + ow;
    double s = 0;
    int64_t n = 0;
    for (int ox = 0; ox < ow; ++ox) {
      if (mask && mask->at(x0 + ox, cy) >= 0.5f) continue;
      const double vx = mxx[ox] - mx[ox] * mx[ox], vy = myy[ox] - my[ox] * my[ox];
      const double cxy = mxy[ox] - mx[ox] * my[ox];
      s += ((2 * mx[ox] * my[ox] + c1) * (2 * cxy + c2)) /
           ((mx[ox] * mx[ox] + my[ox] * my[ox] + c1) * (vx + vy + c2));
      ++n;
    }
    row_sum[size_t(oyy)] = s;
    row_count[size_t(oyy)] = n;
  }, 4);
  ChannelSsim out;
  for (int i = 0; i < oh; ++i) { out.sum += row_sum[size_t(i)]; out.count += row_count[size_t(i)]; }
  return out;
}

}  // namespace

double ssim(const Image& a, const Image& b, const SsimOptions& o, const Image* mask) {
  o.validate();
  require_comparable(a, b, mask, "ssim");
  const int win = 2 * o.radius + 1;
  if (o.padding == SsimPadding::kValid && (a.width < win || a.height < win))
    throw InputError("ssim", "image " + std::to_string(a.width) + "x" + std::to_string(a.height) +
                                 " is smaller than the " + std::to_string(win) + "x" + std::to_string(win) +
                                 " SSIM window; use 'same' padding for tiny images");
  double total = 0;
  for (int c = 0; c < a.channels; ++c) {
    ChannelSsim s = ssim_channel(a, b, c, o, mask);
    if (s.count == 0)
      throw InputError("mask", "the mask excludes every SSIM window centre: nothing left to score");
    total += s.sum / double(s.count);
  }
  return total / a.channels;
}

}  // namespace weathergs::evaluator
