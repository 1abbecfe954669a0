#include "reconstruction/loss.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/parallel.h"
#include "reconstruction/cpu_clones.h"

namespace weathergs::reconstruction {

std::vector<double> ssim_window_1d() {
  std::vector<double> w(kSsimWindow);
  double sum = 0;
  for (int i = 0; i < kSsimWindow; ++i) {
    const double d = i - kSsimWindow / 2;
    w[i] = std::exp(-d * d / (2 * kSsimSigma * kSsimSigma));
    sum += w[i];
  }
  for (double& v : w) v /= sum;
  return w;
}

const char* to_string(MaskNormalization m) { return m == MaskNormalization::kReference ? "reference" : "valid"; }

double psnr_from_mse(double mse) {
  if (!(mse > 1e-10)) return 100.0;
  return -10.0 * std::log10(mse);
}

namespace {

constexpr int kHalf = kSsimWindow / 2;

// y[x] += a s[x], the inner loop of both blur passes; the float version (training) with an AVX2 clone.
WGS_AVX2_CLONES void axpy(float* __restrict y, const float* __restrict s, float a, int n) {
  for (int x = 0; x < n; ++x) y[x] += a * s[x];
}
void axpy(double* __restrict y, const double* __restrict s, double a, int n) {
  for (int x = 0; x < n; ++x) y[x] += a * s[x];
}

// Separable 11x11 Gaussian filter with zero padding ('same' output). The kernel is symmetric, so the
// same function is also its adjoint (used by the backward pass).
template <typename T>
void blur(const T* in, T* out, T* tmp, int w, int h, const T* k) {
  // Horizontal pass on a zero-padded copy of each row: 11 taps, each vectorized over x (the padding
  // contributes exact zeros, so the sums equal the clipped ones).
  std::vector<T> padded(size_t(w) + 2 * kHalf, T(0));
  for (int y = 0; y < h; ++y) {
    std::copy_n(in + int64_t(y) * w, w, padded.begin() + kHalf);
    T* trow = tmp + int64_t(y) * w;
    for (int x = 0; x < w; ++x) trow[x] = 0;
    for (int i = 0; i < kSsimWindow; ++i) axpy(trow, padded.data() + i, k[i], w);
  }
  for (int y = 0; y < h; ++y) {
    T* orow = out + int64_t(y) * w;
    for (int x = 0; x < w; ++x) orow[x] = 0;
    const int a = std::max(0, kHalf - y), b = std::min(kSsimWindow, h + kHalf - y);
    for (int i = a; i < b; ++i) axpy(orow, tmp + int64_t(y + i - kHalf) * w, k[i], w);
  }
}

template <typename T>
struct Workspace {
  // Planar per channel: x (render, target-composited at masked pixels), y (target), products, and the
  // blurred statistics. Reused between calls.
  std::vector<T> planes[3][5], blurred[3][5], tmp[3][5];
  void resize(size_t n) {
    for (auto& c : planes) for (auto& v : c) v.resize(n);
    for (auto& c : blurred) for (auto& v : c) v.resize(n);
    for (auto& c : tmp) for (auto& v : c) v.resize(n);
  }
};

template <typename T>
Workspace<T>& workspace() {
  static thread_local Workspace<T> ws;
  return ws;
}

}  // namespace

template <typename T>
LossValue<T> photometric_loss(const std::vector<T>& render, const std::vector<T>& target,
                              const std::vector<uint8_t>* invalid, int width, int height, T lambda,
                              std::vector<T>* v_render, MaskNormalization normalization) {
  const size_t n = size_t(width) * height;
  WGS_CHECK_EQ(render.size(), n * 3);
  WGS_CHECK_EQ(target.size(), n * 3);
  if (invalid) WGS_CHECK_EQ(invalid->size(), n);
  LossValue<T> out;
  int64_t valid = 0;
  for (size_t i = 0; i < n; ++i) valid += (!invalid || !(*invalid)[i]) ? 1 : 0;
  out.valid_pixels = valid;
  if (v_render) v_render->assign(n * 3, T(0));
  if (valid == 0) return out;
  auto is_valid = [&](size_t i) { return !invalid || !(*invalid)[i]; };
  // kValid: masked pixels take the target's value in the render and count for nothing.
  // kReference: masked pixels take the render's value in the target; every centre counts.
  const bool reference = normalization == MaskNormalization::kReference;
  auto counts = [&](size_t i) { return reference || is_valid(i); };
  const int64_t denominator = reference ? int64_t(n) : valid;

  const std::vector<double> wd = ssim_window_1d();
  T k[kSsimWindow];
  for (int i = 0; i < kSsimWindow; ++i) k[i] = T(wd[i]);
  Workspace<T>& ws = workspace<T>();
  ws.resize(n);
  // Planes 0..4: x, y, x*x, y*y, x*y.
  parallel_for(0, 3, [&](int64_t c) {
    auto& p = ws.planes[c];
    for (size_t i = 0; i < n; ++i) {
      const T x0 = render[i * 3 + c], y0 = target[i * 3 + c];
      const T x = is_valid(i) || reference ? x0 : y0;
      const T y = is_valid(i) || !reference ? y0 : x0;
      p[0][i] = x; p[1][i] = y; p[2][i] = x * x; p[3][i] = y * y; p[4][i] = x * y;
    }
  });
  parallel_for(0, 15, [&](int64_t job) {
    const int c = int(job / 5), m = int(job % 5);
    blur(ws.planes[c][m].data(), ws.blurred[c][m].data(), ws.tmp[c][m].data(), width, height, k);
  });
  // SSIM map and its partial derivatives (stored over the product planes, which are no longer needed).
  const T c1 = T(kSsimC1), c2 = T(kSsimC2);
  const T inv_count = T(1) / (T(3) * T(denominator));
  const T w_ssim = -lambda * inv_count;  // dL/dS at a valid centre
  std::vector<double> ssim_sum(3, 0.0), l1_sum(3, 0.0), se_sum(3, 0.0);
  parallel_for(0, 3, [&](int64_t c) {
    auto& b = ws.blurred[c];
    auto& p = ws.planes[c];
    double s_sum = 0, a_sum = 0, e_sum = 0;
    for (size_t i = 0; i < n; ++i) {
      const T mx = b[0][i], my = b[1][i];
      const T sxx = b[2][i] - mx * mx, syy = b[3][i] - my * my, sxy = b[4][i] - mx * my;
      const T A = T(2) * mx * my + c1, B = T(2) * sxy + c2;
      const T C = mx * mx + my * my + c1, D = sxx + syy + c2;
      const T s = (A * B) / (C * D);
      const bool ok = counts(i);
      if (ok) {
        s_sum += double(s);
        const T d = p[0][i] - p[1][i];
        a_sum += std::abs(double(d));
        e_sum += double(d) * double(d);
      }
      if (v_render) {
        const T w = ok ? w_ssim : T(0);
        const T dA = B / (C * D), dB = A / (C * D), dC = -s / C, dD = -s / D;
        // Reuse planes 2..4 for dL/d(blurred mean x), dL/d(blurred x^2), dL/d(blurred x*y).
        p[2][i] = w * (T(2) * my * (dA - dB) + T(2) * mx * (dC - dD));
        p[3][i] = w * dD;
        p[4][i] = w * T(2) * dB;
      }
    }
    ssim_sum[c] = s_sum;
    l1_sum[c] = a_sum;
    se_sum[c] = e_sum;
  });
  const double count = 3.0 * double(denominator);
  out.ssim = T((ssim_sum[0] + ssim_sum[1] + ssim_sum[2]) / count);
  out.l1 = T((l1_sum[0] + l1_sum[1] + l1_sum[2]) / count);
  out.mse = T((se_sum[0] + se_sum[1] + se_sum[2]) / count);
  out.loss = (T(1) - lambda) * out.l1 + lambda * (T(1) - out.ssim);
  if (!v_render) return out;
  parallel_for(0, 9, [&](int64_t job) {
    const int c = int(job / 3), m = 2 + int(job % 3);
    blur(ws.planes[c][m].data(), ws.blurred[c][m].data(), ws.tmp[c][m].data(), width, height, k);
  });
  const T w_l1 = (T(1) - lambda) * inv_count;
  parallel_for(0, 3, [&](int64_t c) {
    auto& b = ws.blurred[c];
    auto& p = ws.planes[c];
    for (size_t i = 0; i < n; ++i) {
      if (!counts(i)) continue;  // kValid: composited with the target: exactly zero gradient
      const T x = p[0][i], y = p[1][i];  // kReference, masked: x == y, so the L1 sign is 0
      const T d = x - y;
      const T sign = d > T(0) ? T(1) : (d < T(0) ? T(-1) : T(0));
      (*v_render)[i * 3 + c] = w_l1 * sign + b[2][i] + T(2) * x * b[3][i] + y * b[4][i];
    }
  });
  return out;
}

template <typename T>
T ssim_mean(const std::vector<T>& a, const std::vector<T>& b, int width, int height) {
  return photometric_loss<T>(a, b, nullptr, width, height, T(1), nullptr).ssim;
}

template LossValue<float> photometric_loss<float>(const std::vector<float>&, const std::vector<float>&,
                                                  const std::vector<uint8_t>*, int, int, float, std::vector<float>*,
                                                  MaskNormalization);
template LossValue<double> photometric_loss<double>(const std::vector<double>&, const std::vector<double>&,
                                                    const std::vector<uint8_t>*, int, int, double,
                                                    std::vector<double>*, MaskNormalization);
template float ssim_mean<float>(const std::vector<float>&, const std::vector<float>&, int, int);
template double ssim_mean<double>(const std::vector<double>&, const std::vector<double>&, int, int);

}  // namespace weathergs::reconstruction
