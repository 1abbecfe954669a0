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

namespace weathergs::reconstruction::internal {

constexpr int64_t kGaussianChunk = 2048;  // per-Gaussian loops: work per parallel task
constexpr int kEntryGrads = 9;
constexpr int kTilePixels = kTileSize * kTileSize;

template <typename T>
inline bool all_finite(std::initializer_list<T> values) {
  for (T v : values)
    if (!std::isfinite(v)) return false;
  return true;
}

// Integer index on the reference's 16-px tile grid (getRect) from a float coordinate, clamped
// before the conversion (huge or NaN inputs would make the conversion undefined).
template <typename T>
inline int tile_floor_index(T v, int grid) {
  const T c = std::clamp(v / T(kReferenceTile), T(0), T(grid));
  return c == c ? int(c) : 0;
}

inline int reference_tiles(int pixels) { return (pixels + kReferenceTile - 1) / kReferenceTile; }

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
  return T(2) * model_log(T(255) * opacity);
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

// A Gaussian's pixel box, [lo, hi] along one axis (integer values, kept as T): the pixel centres
// within the alpha extent `half` of `mean` (as pixel_range), within the reference rectangle's tiles
// [t0, t1) of 16 px, within the image. Empty (lo > hi) when they do not meet. Float throughout, no
// round trip through int: GCC folds T(int(ceil(v))) to ceil(v) where it inlines ceil, which would
// keep a -0 in one code path and not in another.
template <typename T>
inline void pixel_box(T mean, T half, int t0, int t1, int size, T* lo, T* hi) {
  const T first = T(t0 * kReferenceTile), last = T(std::min(size, t1 * kReferenceTile) - 1);
  *lo = std::clamp(std::ceil(mean - half - T(0.5)), first, last + T(1));
  *hi = std::clamp(std::floor(mean + half - T(0.5)), first - T(1), last);
}

// Writes a blended tile [x0, x1) x [y0, y1) from its planar per-pixel state (index (y - y0) *
// kTileSize + (x - x0)): colour plus the background through the remaining transmittance and, for
// kTraining, the final transmittance and contributor count the backward pass reads. Shared by the
// scalar template (rasterizer.cc) and the SIMD blend (raster_blend_simd.h): the same operations.
// Always inlined: the fused image-only translation unit (raster_image_simd.cc) contracts floating-point
// expressions, so an out-of-line copy from there must never be the one the linker gives the others.
template <bool kTraining, typename T>
inline __attribute__((always_inline)) void write_tile(const RasterSettings<T>& settings, RasterState<T>* s,
                                                      int x0, int y0, int x1, int y1, const T* cr, const T* cg,
                                                      const T* cb, const T* trans, const int32_t* last) {
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const int p = (y - y0) * kTileSize + (x - x0);
      const int64_t pix = int64_t(y) * s->width + x;
      s->image[pix * 3] = cr[p] + trans[p] * settings.background[0];
      s->image[pix * 3 + 1] = cg[p] + trans[p] * settings.background[1];
      s->image[pix * 3 + 2] = cb[p] + trans[p] * settings.background[2];
      if constexpr (kTraining) {
        s->final_transmittance[pix] = trans[p];
        s->n_contrib[pix] = last[p];
      }
    }
}

// The record's pixel box (sp[12..15]) within the tile [x0, x1) x [y0, y1).
template <typename T>
inline void box_in_tile(const T* sp, int x0, int x1, int y0, int y1, int* px0, int* px1, int* py0, int* py1) {
  *px0 = std::max(x0, int(sp[12]));
  *px1 = std::min(x1 - 1, int(sp[13]));
  *py0 = std::max(y0, int(sp[14]));
  *py1 = std::min(y1 - 1, int(sp[15]));
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

// Whether any pixel center of tile (tx, ty) can get alpha >= 1/255 from the splat record `sp`: the
// minimum over the tile's pixel-center rectangle of q(d) = d^T conic d (the splat's power is -q/2)
// against q_max = 2 ln(255 o). q is convex, so the minimum is 0 with the mean inside the rectangle,
// else on one of its edges, where it is a 1-D quadratic minimised in closed form. The margin (1e-3
// absolute on q, 1e-4 relative; alpha changes by < 0.06 %) covers the float rounding of the
// kernels' per-pixel power and exp (< 1e-5 on q), so no tile with a contributing pixel is dropped.
// q_max = 2 ln(255 o) with that margin (the record's sp[11]).
template <typename T>
inline bool tile_touched(const T* sp, T q_max, T inv_ca, T inv_cc, int tx, int ty, int width, int height) {
  const T ca = sp[2], cb = sp[3], cc = sp[4];
  const T x_lo = T(tx * kTileSize) + T(0.5) - sp[0];
  const T x_hi = T(std::min(width, (tx + 1) * kTileSize)) - T(0.5) - sp[0];
  const T y_lo = T(ty * kTileSize) + T(0.5) - sp[1];
  const T y_hi = T(std::min(height, (ty + 1) * kTileSize)) - T(0.5) - sp[1];
  if (x_lo <= T(0) && x_hi >= T(0) && y_lo <= T(0) && y_hi >= T(0)) return true;
  auto q = [&](T dx, T dy) { return ca * dx * dx + T(2) * cb * dx * dy + cc * dy * dy; };
  T q_min = std::numeric_limits<T>::infinity();
  for (T dx : {x_lo, x_hi}) q_min = std::min(q_min, q(dx, std::clamp(-cb * dx * inv_cc, y_lo, y_hi)));
  for (T dy : {y_lo, y_hi}) q_min = std::min(q_min, q(std::clamp(-cb * dy * inv_ca, x_lo, x_hi), dy));
  return q_min <= q_max;
}

// The record's pixel box (sp[12..15]) from its alpha extents (sp[9], sp[10]) and the reference
// rectangle [x0, x1) x [y0, y1) of 16-px tiles, and the rectangle r of kTileSize tiles holding it
// (all zero when the box is empty).
template <typename T>
inline void set_pixel_box(const RasterState<T>* s, T* sp, int x0, int y0, int x1, int y1, int32_t* r) {
  T bx0 = T(0), bx1 = T(-1), by0 = T(0), by1 = T(-1);
  if (sp[9] >= T(0)) {
    pixel_box(sp[0], sp[9], x0, x1, s->width, &bx0, &bx1);
    pixel_box(sp[1], sp[10], y0, y1, s->height, &by0, &by1);
  }
  if (bx0 > bx1 || by0 > by1) {
    bx0 = by0 = T(0);
    bx1 = by1 = T(-1);
    r[0] = r[1] = r[2] = r[3] = 0;
  } else {
    r[0] = int(bx0) / kTileSize;
    r[1] = int(by0) / kTileSize;
    r[2] = int(bx1) / kTileSize + 1;
    r[3] = int(by1) / kTileSize + 1;
  }
  sp[12] = bx0;
  sp[13] = bx1;
  sp[14] = by0;
  sp[15] = by1;
}

// Marks Gaussian i as not rendered (the state of a culled Gaussian).
template <typename T>
inline void clear_gaussian(RasterState<T>* s, int64_t i) {
  s->radius[i] = 0;
  for (int k = 0; k < 4; ++k) s->rect[i * 4 + k] = 0;
  s->tile_mask[i] = 0;
}

// The part of the per-Gaussian preprocessing that follows the projection, shared by the scalar
// template (rasterizer.cc) and the float SIMD one (preprocess_simd.cc): from the projected mean,
// the 2D covariance [[a, b], [b, c]] (low-pass included), the camera depth z (> the near plane), the
// clamped SH colour and the opacity logit, the reference's radius and conic, the tile rectangle, the
// packed record and the opacity-aware tile mask. Leaves the Gaussian cleared (clear_gaussian) when
// the covariance is degenerate, a value is not finite or no tile is touched.
template <typename T>
inline void finish_gaussian(RasterState<T>* s, int64_t i, T mean_x, T mean_y, T a, T b, T c, T z, const T color[3],
                            uint8_t clamped, T opacity_logit) {
  const T det = a * c - b * b;
  if (!(det > T(0))) return;
  const T mid = T(0.5) * (a + c);
  const T root = std::sqrt(std::max(T(kMinEigenGap), mid * mid - det));
  const T lambda = std::max(mid + root, mid - root);
  const T radius = std::ceil(T(3) * std::sqrt(lambda));
  const T conic_a = c / det, conic_b = -b / det, conic_c = a / det;
  if (!all_finite<T>({mean_x, mean_y, a, b, c, radius, conic_a, conic_b, conic_c})) return;
  // Tile rectangle exactly as the reference's getRect (16-px tiles), in its pixel-center-at-integer frame.
  const T px = mean_x - T(0.5), py = mean_y - T(0.5);
  const int gx = reference_tiles(s->width), gy = reference_tiles(s->height);
  const int x0 = tile_floor_index(px - radius, gx);
  const int y0 = tile_floor_index(py - radius, gy);
  const int x1 = tile_floor_index(px + radius + T(kReferenceTile - 1), gx);
  const int y1 = tile_floor_index(py + radius + T(kReferenceTile - 1), gy);
  if ((x1 - x0) * (y1 - y0) == 0) return;
  if (!all_finite<T>({color[0], color[1], color[2]})) return;
  s->radius[i] = int32_t(std::min<T>(radius, T(std::numeric_limits<int32_t>::max() / 2)));
  s->mean2d[i * 2] = mean_x; s->mean2d[i * 2 + 1] = mean_y;
  s->cov2d[i * 3] = a; s->cov2d[i * 3 + 1] = b; s->cov2d[i * 3 + 2] = c;
  s->conic[i * 3] = conic_a; s->conic[i * 3 + 1] = conic_b; s->conic[i * 3 + 2] = conic_c;
  s->opacity[i] = sigmoid(opacity_logit);
  for (int k = 0; k < 3; ++k) s->color[i * 3 + k] = color[k];
  s->clamped[i] = clamped;
  s->depth[i] = z;
  T* sp = &s->splat[i * kSplatFloats];
  sp[0] = mean_x; sp[1] = mean_y; sp[2] = conic_a; sp[3] = conic_b; sp[4] = conic_c;
  sp[5] = s->opacity[i]; sp[6] = color[0]; sp[7] = color[1]; sp[8] = color[2];
  const T q_max = alpha_q_max(sp[5]);
  sp[9] = alpha_extent(q_max, a);
  sp[10] = alpha_extent(q_max, c);
  // q limit of the per-row spans (row_span) with tile_touched's margin.
  sp[11] = q_max < T(0) ? T(-1) : q_max * T(1.0001) + T(1e-3);
  // Opacity-aware tiles: the kernels blend only the pixel box, the pixels of the 3-sigma rectangle
  // within the alpha extent, so tiles that no such pixel lies in get no entry (same images and
  // gradients, fewer entries to bin, sort and replay). `radius` stays the reference's (densification
  // uses it).
  int32_t* r = &s->rect[i * 4];
  set_pixel_box(s, sp, x0, y0, x1, y1, r);
  // Tiles of the rectangle that the ellipse misses (its corners, for a tilted or elongated
  // splat) get no entry either. A rectangle one tile high or wide is the ellipse's own extent,
  // so all of its tiles are kept untested; rectangles of more than 64 tiles keep all of theirs.
  const int area = (r[2] - r[0]) * (r[3] - r[1]);
  if (area > 0 && area <= kMaskTiles) {
    uint64_t mask = area == kMaskTiles ? ~uint64_t(0) : (uint64_t(1) << area) - 1;
    if (r[2] - r[0] > 1 && r[3] - r[1] > 1) {
      mask = 0;
      const T inv_ca = T(1) / sp[2], inv_cc = T(1) / sp[4];
      for (int ty = r[1], bit = 0; ty < r[3]; ++ty)
        for (int tx = r[0]; tx < r[2]; ++tx, ++bit)
          if (tile_touched(sp, sp[11], inv_ca, inv_cc, tx, ty, s->width, s->height)) mask |= uint64_t(1) << bit;
    }
    s->tile_mask[i] = mask;
    if (mask == 0) r[0] = r[1] = r[2] = r[3] = 0;
  }
}

// Per Gaussian (parallel): projection, 2D covariance, SH colour, then finish_gaussian. The float
// version (preprocess_simd.cc) does the arithmetic of the scalar template (rasterizer.cc) for 4 or 8
// Gaussians at a time (the tile kernels' width), operation by operation in the same order, so both
// give the same bits (test reconstruction/rasterizer); preprocess_scalar runs the template in float.
void preprocess_simd(const GaussianSet<float>& g, const RasterCamera<float>& cam, const RasterSettings<float>& settings,
                     RasterState<float>* s);
void preprocess_scalar(const GaussianSet<float>& g, const RasterCamera<float>& cam,
                       const RasterSettings<float>& settings, RasterState<float>* s);

// The float tile kernels (raster_simd.cc): 4 or 8 pixels at a time, lane by lane the per-pixel
// operations of the scalar templates of rasterizer.cc; every width gives bit-identical results
// (except the fused image-only render below).
void render_tile_simd(const RasterSettings<float>& settings, RasterState<float>* s, int64_t tile);
void backward_tile_simd(const RasterSettings<float>& settings, RasterState<float>* s, const std::vector<float>& v_image,
                        int64_t tile);

// The lane count of the tile kernels: 8 where the CPU has AVX2, else 4, chosen once per process.
// set_tile_kernel_width switches it (tests, benchmarks); it returns false and changes nothing for a
// width other than 4 or 8 or one the CPU cannot run. Not to be called while a rasterization runs.
int tile_kernel_width();
bool set_tile_kernel_width(int width);

// The image-only render (RasterOutputs::kImage) at 8 lanes on a CPU with FMA runs
// render_image_tile_fused (raster_image_simd.cc): the same blend compiled with fused multiply-add,
// ~15 % faster. Its images equal the training forward's up to rounding (and the effects of rounding
// on the 1/255 and transmittance cut-offs), not bit for bit; with 1 or 2 threads they are identical
// (test RasterizerTest.ImageOnlyForwardMatchesTheTrainingForward). fused_image_kernel() says whether
// renders take that path at the current width.
bool fused_image_kernel();
void render_image_tile_fused(const RasterSettings<float>& settings, RasterState<float>* s, int64_t tile);

}  // namespace weathergs::reconstruction::internal
