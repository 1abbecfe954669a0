// The float forward blend of the rasterizer, W pixels at a time with GCC/Clang vector extensions, and
// the vector helpers it shares with the backward kernels. Include only from the SIMD tile-kernel
// translation units: raster_simd.cc (the training forward and the backward, no fused multiply-add,
// bit-identical at 4 and 8 lanes) and raster_image_simd.cc (the image-only render, compiled with
// fused multiply-add). Everything here has internal linkage on purpose: each translation unit
// compiles its own copy under its own floating-point contraction, and no copy may be merged with
// the other's by the linker (one template with two meanings would break the one-definition rule).
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>

#include "reconstruction/raster_internal.h"
#include "reconstruction/simd_lanes.h"

namespace weathergs::reconstruction::internal {
namespace {  // NOLINT(google-build-namespaces): per-translation-unit copies, see above

template <typename V>
WGS_ALWAYS_INLINE V splat(float v) {
  return V{} + v;
}
template <typename V>
WGS_ALWAYS_INLINE V vmin(V a, V b) { return a < b ? a : b; }
template <typename V>
WGS_ALWAYS_INLINE V vmax(V a, V b) { return a > b ? a : b; }
template <typename V, typename S>
WGS_ALWAYS_INLINE V load(const S* p) { V v; std::memcpy(&v, p, sizeof(V)); return v; }
template <typename V, typename S>
WGS_ALWAYS_INLINE void store(S* p, V v) { std::memcpy(p, &v, sizeof(V)); }

// blend_exp(float) lane by lane, same operations in the same order.
template <int W>
WGS_ALWAYS_INLINE typename Lanes<W>::f blend_exp_v(typename Lanes<W>::f x) {
  using vf = typename Lanes<W>::f;
  using vi = typename Lanes<W>::i;
  x = vmax(x, splat<vf>(-87.0f));
  const vf t = x * 1.44269504088896341f;
  const vi n = __builtin_convertvector(t - 0.5f, vi);
  const vf f = t - __builtin_convertvector(n, vf);
  vf q = splat<vf>(kExp2Poly[0]);
  for (int k = 1; k < 5; ++k) q = q * f + kExp2Poly[k];
  const vf p = q * f + 1.0f;
  const vi bits = (n + 127) << 23;
  vf scale;
  std::memcpy(&scale, &bits, sizeof(vf));
  return p * scale;
}

// Whether any lane of a comparison mask (0 or -1 per lane) is set.
template <int W>
WGS_ALWAYS_INLINE bool any_lane(typename Lanes<W>::i m) {
  if constexpr (W == 8) {
    typename Lanes<4>::i lo, hi;
    std::memcpy(&lo, &m, sizeof lo);
    std::memcpy(&hi, reinterpret_cast<const char*>(&m) + sizeof lo, sizeof hi);
    return any_lane<4>(lo | hi);
  } else {
    static_assert(W == 4);
    uint64_t a, b;
    std::memcpy(&a, &m, 8);
    std::memcpy(&b, reinterpret_cast<const char*>(&m) + 8, 8);
    return (a | b) != 0;
  }
}

template <typename V>
WGS_ALWAYS_INLINE float hsum4(V v) {
  return ((v[0] + v[1]) + v[2]) + v[3];
}

template <int W>
WGS_ALWAYS_INLINE typename Lanes<W>::f lane_centers(int x0) {
  typename Lanes<W>::f c;
  for (int l = 0; l < W; ++l) c[l] = float(l) + 0.5f + float(x0);
  return c;
}

// kTraining: the training forward, whose per-pixel arithmetic the backward pass replays; it also
// keeps each pixel's final transmittance and contributor count. Otherwise an image-only render: the
// same blend without those outputs, its block power in Horner form (equal up to rounding).
template <int W, bool kTraining>
WGS_ALWAYS_INLINE void render_tile(const RasterSettings<float>& settings, RasterState<float>* s, int64_t t) {
  using vf = typename Lanes<W>::f;
  using vi = typename Lanes<W>::i;
  const int x0 = int(t % s->tiles_x) * kTileSize, y0 = int(t / s->tiles_x) * kTileSize;
  const int x1 = std::min(s->width, x0 + kTileSize), y1 = std::min(s->height, y0 + kTileSize);
  alignas(64) float trans[kTilePixels], cr[kTilePixels], cg[kTilePixels], cb_[kTilePixels];
  alignas(64) int32_t last[kTilePixels], done[kTilePixels];
  for (int p = 0; p < kTilePixels; ++p) {
    const int x = x0 + p % kTileSize, y = y0 + p / kTileSize;
    trans[p] = 1.f;
    cr[p] = cg[p] = cb_[p] = 0.f;
    last[p] = 0;
    done[p] = (x < x1 && y < y1) ? 0 : -1;  // outside the image: never blended
  }
  const int64_t npix = int64_t(x1 - x0) * (y1 - y0);
  int64_t num_done = 0;
  // Per tile row, bit x set when pixel x is done (stopped, or outside the image). A row whose pixels
  // in a Gaussian's range are all done is skipped: those pixels would not change (measured on the
  // bench scene: a tile list holds ~800 entries, its pixels' last contributors are at ~120 on
  // average, and tiles with a few unsaturated pixels run through the whole list).
  uint32_t row_done[kTileSize];
  auto refresh_row = [&](int r) {
    uint32_t bits = 0;
    for (int x = 0; x < kTileSize; ++x) bits |= uint32_t(done[r * kTileSize + x] != 0) << x;
    row_done[r] = bits;
  };
  for (int r = 0; r < kTileSize; ++r) refresh_row(r);
  vf block_power[kTilePixels / W];  // the second pass's blocks: power, first pixel
  int block_pixel[kTilePixels / W];
  const int64_t begin = s->tile_offset[t], end = s->tile_offset[t + 1];
  const vf lane_center = lane_centers<W>(x0);
  constexpr int64_t kPrefetch = 8;  // records are scattered over memory: fetch ahead of use
  for (int64_t k = begin; k < end && num_done < npix; ++k) {
    if (k + kPrefetch < end) __builtin_prefetch(&s->splat[int64_t(s->tile_gaussian[k + kPrefetch]) * kSplatFloats]);
    const float* sp = &s->splat[int64_t(s->tile_gaussian[k]) * kSplatFloats];
    int px0, px1, py0, py1;  // the box is empty where alpha never reaches 1/255 (sp[9] < 0)
    box_in_tile(sp, x0, x1, y0, y1, &px0, &px1, &py0, &py1);
    if (px0 > px1) continue;
    const vf mx = splat<vf>(sp[0]), ca = splat<vf>(sp[2]), cb = splat<vf>(sp[3]), cc = splat<vf>(sp[4]);
    const vf o = splat<vf>(sp[5]), r = splat<vf>(sp[6]), g = splat<vf>(sp[7]), b = splat<vf>(sp[8]);
    // Below this power every lane's alpha is < 1/255 (sp[11] carries the margin against the float
    // rounding of the power and blend_exp, see tile_touched): a block with no lane at or above it and
    // not done changes nothing, so it is skipped before the exp, the loads and the stores. The margin
    // (>= 5e-4 in power) also covers the fused image-only kernel, whose power and exp round
    // differently by ~1e-6 relative.
    const vf power_min = splat<vf>(-0.5f * sp[11]);
    const vi contributor = vi{} + int32_t(k - begin + 1);
    const int bx0 = ((px0 - x0) / W) * W, bx1 = px1 - x0;
    const uint32_t span = ((uint32_t(2) << (px1 - x0)) - 1) & ~((uint32_t(1) << (px0 - x0)) - 1);
    // Two passes: first the blocks that a live pixel can take alpha >= 1/255 from, with their
    // power (every candidate is written, and kept by advancing the count: no branch on the test),
    // then the blend of exactly those blocks (independent of each other, no data-dependent branch).
    // The same blocks in the same order with the same operations as one pass: the same bits.
    // Measured 6-10 % faster than testing and blending block by block (benchmarks/README.md).
    int num_blocks = 0;
    for (int py = py0; py <= py1; ++py) {
      if ((row_done[py - y0] & span) == span) continue;
      const vf dy = splat<vf>(sp[1] - (float(py) + 0.5f));
      // Image-only: the same quadratic in Horner form, (pa dx + pb) dx + pc, two fused multiply-adds
      // in the fused kernel (raster_image_simd.cc).
      [[maybe_unused]] const vf pa = -0.5f * ca, pb = -(cb * dy), pc = -0.5f * (cc * dy * dy);
      const int row = (py - y0) * kTileSize;
      for (int bx = bx0; bx <= bx1; bx += W) {
        const int p = row + bx;
        const vf dx = mx - (lane_center + float(bx));
        vf power;
        if constexpr (kTraining) power = -0.5f * (ca * dx * dx + cc * dy * dy) - cb * dx * dy;
        else power = (pa * dx + pb) * dx + pc;
        const vi live = load<vi>(&done[p]) == 0;
        block_power[num_blocks] = power;
        block_pixel[num_blocks] = p;
        num_blocks += any_lane<W>((power >= power_min) & live);
      }
    }
    vi stopped = {};
    for (int j = 0; j < num_blocks; ++j) {
      const int p = block_pixel[j];
      const vf power = block_power[j];
      const vi live = load<vi>(&done[p]) == 0;
      const vf alpha = vmin(splat<vf>(float(kAlphaMax)), o * blend_exp_v<W>(vmin(power, splat<vf>(0.f))));
      const vf tp = load<vf>(&trans[p]);
      const vf test_t = tp * (1.f - alpha);
      const vi ok = (power <= 0.f) & (alpha >= float(kAlphaMin)) & live;
      const vi stop = ok & (test_t < float(kTransmittanceMin));
      const vi add = ok & ~stop;
      const vf w = add ? alpha * tp : splat<vf>(0.f);
      store(&cr[p], load<vf>(&cr[p]) + r * w);
      store(&cg[p], load<vf>(&cg[p]) + g * w);
      store(&cb_[p], load<vf>(&cb_[p]) + b * w);
      store(&trans[p], add ? test_t : tp);
      if constexpr (kTraining) store(&last[p], add ? contributor : load<vi>(&last[p]));
      store(&done[p], load<vi>(&done[p]) | stop);
      stopped -= stop;
    }
    int64_t entry_stops = 0;
    for (int l = 0; l < W; ++l) entry_stops += stopped[l];
    if (entry_stops > 0) {
      num_done += entry_stops;
      for (int py = py0; py <= py1; ++py) refresh_row(py - y0);
    }
  }
  write_tile<kTraining>(settings, s, x0, y0, x1, y1, cr, cg, cb_, trans, last);
}

}  // namespace
}  // namespace weathergs::reconstruction::internal
