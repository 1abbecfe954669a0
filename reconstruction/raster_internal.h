// Internal to the rasterizer (rasterizer.cc, raster_simd.cc): the per-pixel blend arithmetic shared
// by the scalar templates and the float SIMD kernels, so that both compute identical values.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <vector>

#include "reconstruction/rasterizer.h"

namespace weathergs::recon::internal {

constexpr int64_t kGaussianChunk = 2048;  // per-Gaussian loops: work per parallel task
constexpr int kEntryGrads = 9;
constexpr int kTilePixels = kTileSize * kTileSize;

template <typename T>
inline bool all_finite(std::initializer_list<T> values) {
  for (T v : values)
    if (!std::isfinite(v)) return false;
  return true;
}

// Integer tile index from a float coordinate, clamped before the conversion (huge or NaN inputs
// would make the conversion undefined).
template <typename T>
inline int tile_floor_index(T v, int grid) {
  const T c = std::clamp(v / T(kTileSize), T(0), T(grid));
  return c == c ? int(c) : 0;
}

// exp for the blend weights. float: a branch-free base-2 reduction, exp(x) = 2^n 2^f with
// n = round(x log2 e) and f in [-0.5, 0.5], and 2^f = 1 + f q(f) with q of degree 4 (a least-squares
// fit in relative error, 9e-8 on [-0.5, 0.5]; exp(0) = 1 exactly): within 4.4e-7 relative of exp on
// [-5.6, 0], the range a blend weight >= 1/255 comes from, 4e-6 down to -87 (the rounding of x log2 e
// grows with |x|). Test BlendExpIsAccurate. The compiler vectorizes it, unlike libm's expf. double
// (the finite-difference tests): std::exp. Arguments are <= 0 here; below -87 the result is 0-ish (1e-38).
constexpr float kExp2Poly[5] = {0.001326468656770885f, 0.009671501815319061f, 0.05550733581185341f,
                                0.24022242426872253f, 0.6931470036506653f};
inline float blend_exp(float x) {
  x = std::max(x, -87.0f);
  const float t = x * 1.44269504088896341f;
  const int n = int(t - 0.5f);  // round to nearest for t <= 0 (truncation toward zero)
  const float f = t - float(n);
  float q = kExp2Poly[0];
  for (int k = 1; k < 5; ++k) q = q * f + kExp2Poly[k];
  const float p = q * f + 1.0f;
  int32_t bits = (n + 127) << 23;
  float scale;
  std::memcpy(&scale, &bits, 4);
  return p * scale;
}
inline double blend_exp(double x) { return std::exp(x); }

// The largest d^T conic d at which alpha = o exp(-d^T conic d / 2) still reaches 1/255:
// 2 ln(255 o); -1 when the opacity alone is below 1/255 (alpha <= o can never reach it).
template <typename T>
inline T alpha_q_max(T opacity) {
  if (!(opacity >= T(kAlphaMin))) return T(-1);
  return T(2) * std::log(T(255) * opacity);
}

// Half extent (px), along an axis with 2D variance cov_diag, of the region where a Gaussian's alpha
// can reach 1/255: the bounding box of the ellipse d^T conic d <= q_max (alpha_q_max), widened by
// one pixel against rounding. Outside it the blend skips every pixel anyway, so restricting the
// loops to it does not change the result. Negative when q_max is.
template <typename T>
inline T alpha_extent(T q_max, T cov_diag) {
  if (q_max < T(0)) return T(-1);
  return std::sqrt(q_max * cov_diag) + T(1);
}

// Pixel range [lo, hi] of centers (i + 0.5) within `half` of `mean`, clipped to [lo_clip, hi_clip].
template <typename T>
inline void pixel_range(T mean, T half, int lo_clip, int hi_clip, int* lo, int* hi) {
  const T a = std::clamp(std::ceil(mean - half - T(0.5)), T(lo_clip), T(hi_clip + 1));
  const T b = std::clamp(std::floor(mean + half - T(0.5)), T(lo_clip - 1), T(hi_clip));
  *lo = int(a);
  *hi = int(b);
}

// Pixel range [*lo, *hi] (within [lo, hi] on entry) of row py where the splat record `sp` can reach
// alpha >= 1/255: the row's chord of the ellipse d^T conic d <= sp[11], widened by one pixel, with
// d = mean - pixel center. Empty (lo > hi) when the row misses the ellipse. Conservative like the
// extents (the margin in sp[11] and the pixel), so restricting a row to it changes no result.
template <typename T>
inline void row_span(const T* sp, T inv_ca, int py, int* lo, int* hi) {
  const T dy = sp[1] - (T(py) + T(0.5));
  // q(dx) = ca dx^2 + 2 cb dx dy + cc dy^2 is smallest at dx = -cb dy / ca, where it is dy^2 (cc - cb^2 / ca).
  const T rest = sp[11] - dy * dy * (sp[4] - sp[3] * sp[3] * inv_ca);
  if (!(rest >= T(0))) {
    *lo = *hi + 1;
    return;
  }
  const T half = std::sqrt(rest * inv_ca) + T(1);
  const T center = sp[0] + sp[3] * dy * inv_ca;  // the pixel center where dx = -cb dy / ca
  int a, b;
  pixel_range(center, half, *lo, *hi, &a, &b);
  *lo = a;
  *hi = b;
}

// The blend weight of the reference: power of the 2D Gaussian at offset (dx, dy) and
// alpha = min(0.99, o exp(power)); shared by forward and backward so both see identical values.
template <typename T>
inline T splat_power(T ca, T cb, T cc, T dx, T dy) {
  return T(-0.5) * (ca * dx * dx + cc * dy * dy) - cb * dx * dy;
}

// The float tile kernels (raster_simd.cc): 4 or 8 pixels at a time, lane by lane the per-pixel
// operations of the scalar templates of rasterizer.cc; every width gives bit-identical results.
void render_tile_simd(const RasterSettings<float>& settings, RasterState<float>* s, int64_t tile);
void backward_tile_simd(const RasterSettings<float>& settings, RasterState<float>* s, const std::vector<float>& v_image,
                        int64_t tile);

// The lane count of the tile kernels: 8 where the CPU has AVX2, else 4, chosen once per process.
// set_tile_kernel_width switches it (tests, benchmarks); it returns false and changes nothing for a
// width other than 4 or 8 or one the CPU cannot run. Not to be called while a rasterization runs.
int tile_kernel_width();
bool set_tile_kernel_width(int width);

}  // namespace weathergs::recon::internal
