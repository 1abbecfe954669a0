#include "evaluator/metrics.h"

#include <algorithm>
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

// Inner loops of the separable filter, cloned for AVX2+FMA with a portable default; the loader picks
// the clone the CPU supports. Results differ between the clones only by FMA rounding (~1e-16).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define WGS_SIMD_CLONES __attribute__((target_clones("arch=haswell", "default")))
#else
#define WGS_SIMD_CLONES
#endif

// dst[i] = sum_k g[k] src[i + k]: one filtered row (horizontal pass). The 11-tap case (the default
// window) is spelled out so each output accumulates in a register.
WGS_SIMD_CLONES void filter_h11(double* __restrict dst, const double* __restrict src, const double* g, int n) {
  const double g0 = g[0], g1 = g[1], g2 = g[2], g3 = g[3], g4 = g[4], g5 = g[5], g6 = g[6], g7 = g[7],
               g8 = g[8], g9 = g[9], g10 = g[10];
  for (int i = 0; i < n; ++i)
    dst[i] = g0 * src[i] + g1 * src[i + 1] + g2 * src[i + 2] + g3 * src[i + 3] + g4 * src[i + 4] +
             g5 * src[i + 5] + g6 * src[i + 6] + g7 * src[i + 7] + g8 * src[i + 8] + g9 * src[i + 9] +
             g10 * src[i + 10];
}
void filter_h(double* dst, const double* src, const double* g, int taps, int n) {
  if (taps == 11) return filter_h11(dst, src, g, n);
  for (int i = 0; i < n; ++i) {
    double s = 0;
    for (int k = 0; k < taps; ++k) s += g[k] * src[i + k];
    dst[i] = s;
  }
}

// dst[i] = sum_k g[k] rows[k][i] (vertical pass); rows outside the image point at a zero row.
WGS_SIMD_CLONES void filter_v11(double* __restrict dst, const double* const* rows, const double* g, int n) {
  const double *r0 = rows[0], *r1 = rows[1], *r2 = rows[2], *r3 = rows[3], *r4 = rows[4], *r5 = rows[5],
               *r6 = rows[6], *r7 = rows[7], *r8 = rows[8], *r9 = rows[9], *r10 = rows[10];
  const double g0 = g[0], g1 = g[1], g2 = g[2], g3 = g[3], g4 = g[4], g5 = g[5], g6 = g[6], g7 = g[7],
               g8 = g[8], g9 = g[9], g10 = g[10];
  for (int i = 0; i < n; ++i)
    dst[i] = g0 * r0[i] + g1 * r1[i] + g2 * r2[i] + g3 * r3[i] + g4 * r4[i] + g5 * r5[i] + g6 * r6[i] +
             g7 * r7[i] + g8 * r8[i] + g9 * r9[i] + g10 * r10[i];
}
void filter_v(double* dst, const double* const* rows, const double* g, int taps, int n) {
  if (taps == 11) return filter_v11(dst, rows, g, n);
  for (int i = 0; i < n; ++i) {
    double s = 0;
    for (int k = 0; k < taps; ++k) s += g[k] * rows[k][i];
    dst[i] = s;
  }
}

// Sum of the SSIM map over one output row, skipping masked centres (mask_row may be null).
WGS_SIMD_CLONES double ssim_row(const double* mx, const double* my, const double* mxx, const double* myy,
                                const double* mxy, const float* mask_row, int n, double c1, double c2,
                                int64_t& count) {
  double s = 0;
  int64_t k = 0;
  for (int i = 0; i < n; ++i) {
    const double vx = mxx[i] - mx[i] * mx[i], vy = myy[i] - my[i] * my[i];
    const double cxy = mxy[i] - mx[i] * my[i];
    const double v = ((2 * mx[i] * my[i] + c1) * (2 * cxy + c2)) / ((mx[i] * mx[i] + my[i] * my[i] + c1) * (vx + vy + c2));
    const bool keep = !mask_row || mask_row[i] < 0.5f;
    s += keep ? v : 0.0;
    k += keep;
  }
  count = k;
  return s;
}

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
  // Input index i of a padded row is image column i - pad (zeros outside: "same" padding).
  const int pad = valid ? 0 : r;
  const size_t n_in = size_t(w + 2 * pad), n_out = size_t(ow);

  // Output rows are processed in fixed bands (independent of the thread count). Each band streams
  // its input rows through a ring of `taps` horizontally filtered rows of five planes
  // (x, y, xx, yy, xy; structure of arrays), so the working set stays in cache.
  constexpr int kBandRows = 32;
  std::vector<double> row_sum(size_t(oh), 0.0);
  std::vector<int64_t> row_count(size_t(oh), 0);
  parallel_for_chunks(0, oh, kBandRows, [&](int64_t, int64_t band_lo, int64_t band_hi) {
    std::vector<double> in(n_in * 5, 0.0);          // one padded input row, five planes
    std::vector<double> ring(size_t(taps) * 5 * n_out);  // [slot][plane][x]
    std::vector<double> m(5 * n_out);
    std::vector<double> zeros(n_out, 0.0);
    std::vector<const double*> rows(static_cast<size_t>(taps));
    auto ring_row = [&](int y, int q) { return &ring[(size_t(y % taps) * 5 + size_t(q)) * n_out]; };
    int next_row = std::max(0, y0 + int(band_lo) - r);  // first input row not yet filtered
    for (int64_t oyy = band_lo; oyy < band_hi; ++oyy) {
      const int cy = y0 + int(oyy);
      for (; next_row <= std::min(h - 1, cy + r); ++next_row) {
        const int y = next_row;
        for (int x = 0; x < w; ++x) {
          const double va = a.at(x, y, c), vb = b.at(x, y, c);
          const size_t i = size_t(x + pad);
          in[i] = va; in[n_in + i] = vb; in[2 * n_in + i] = va * va; in[3 * n_in + i] = vb * vb;
          in[4 * n_in + i] = va * vb;
        }
        // Output column ox is centred on padded index ox + r.
        for (int q = 0; q < 5; ++q) filter_h(ring_row(y, q), &in[size_t(q) * n_in], g.data(), taps, ow);
      }
      for (int q = 0; q < 5; ++q) {
        for (int k = -r; k <= r; ++k) {
          const int y = cy + k;  // rows outside the image: zero padding (only reachable in "same")
          rows[size_t(k + r)] = (y < 0 || y >= h) ? zeros.data() : ring_row(y, q);
        }
        filter_v(&m[size_t(q) * n_out], rows.data(), g.data(), taps, ow);
      }
      const double *mx = m.data(), *my = mx + n_out, *mxx = my + n_out, *myy = mxx + n_out, *mxy = myy + n_out;
      const float* mask_row = mask ? &mask->data[size_t(cy) * size_t(w) + size_t(x0)] : nullptr;
      int64_t count = 0;
      row_sum[size_t(oyy)] = ssim_row(mx, my, mxx, myy, mxy, mask_row, ow, c1, c2, count);
      row_count[size_t(oyy)] = count;
    }
  });
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
