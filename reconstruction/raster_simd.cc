// The float tile kernels of the rasterizer, W pixels at a time with GCC/Clang vector extensions.
// One template, two widths chosen once at run time (raster_internal.h): 4 lanes (SSE2, every x86-64;
// NEON on arm64) and 8 (AVX2). Each lane computes for its pixel the per-pixel arithmetic of the
// scalar kernels of rasterizer.cc (which serve double; they sum a backward entry's terms in pixel
// order, these 8 lanes wide at either width): only IEEE element-wise operations and no fused
// multiply-add (the library compiles with -ffp-contract=off: reconstruction/CMakeLists.txt), so both
// widths give bit-identical images and gradients (test reconstruction/rasterizer). The image-only
// render at 8 lanes is the exception: it runs the fused copy of raster_image_simd.cc where the CPU has
// FMA (faster, equal to these up to rounding). A 16-lane AVX-512F variant of
// this template was measured 2.6x slower than 8 lanes (130 vs 50 ms per iteration, bench_reconstruction
// 300x200/50k) and is not built. The lanes of a block that lie outside a Gaussian's
// alpha extent get alpha < 1/255 and are skipped by the same test as any other pixel, so wider
// blocks change the work, never the result.
#include <algorithm>
#include <atomic>
#include <cstring>

#include "reconstruction/raster_blend_simd.h"
#include "reconstruction/raster_internal.h"
#include "reconstruction/simd_lanes.h"

namespace weathergs::reconstruction::internal {

namespace {

// The backward replay, back to front per pixel. Per pixel it keeps the transmittance (recovered
// from the final one as T_k = T_(k+1) / (1 - alpha_k)) and one scalar, S.d: the dot product of dL/dpixel
// with the colour the entries behind the current one contributed (gsplat's front-colour buffer,
// in its scalar form since dL/dpixel is fixed per pixel). Then
//   dL/dalpha_k = (c_k.d) T_k - (S.d) / (1 - alpha_k)  [- T_final / (1 - alpha_k) bg.d],
// equal to the reference's (c_k - accum_rec) . d T_k recursion over 7 per-pixel arrays. The
// per-entry sums collect, per pixel, v_power dx, v_power dy, v_power dx^2, v_power dx dy, v_power dy^2
// (v_power = dL/dpower), gauss v_alpha and w d; the conic and opacity factors are applied once per
// entry. They go to an 8-lane accumulator that receives the 8-pixel groups of each row in column order,
// rows top to bottom (the 4-lane kernel feeds its two halves): the same additions at either width.
// Pixels a group covers outside the Gaussian's span add only zeros of either sign (never -0 into +0
// that would flip it: a sum that starts at +0 stays +0 under +-0), so skipped rows change no bits.
// kBackground: the background is not black; with a black one its term is exactly zero and left out.
template <int W, bool kBackground>
WGS_ALWAYS_INLINE void backward_tile(const RasterSettings<float>& settings, RasterState<float>* s,
                                     const std::vector<float>& v_image, int64_t t) {
  using vf = typename Lanes<W>::f;
  using vi = typename Lanes<W>::i;
  using v4f = typename Lanes<4>::f;
  using v8f = typename Lanes<8>::f;
  constexpr int kSums = kEntryGrads;
  const int x0 = int(t % s->tiles_x) * kTileSize, y0 = int(t / s->tiles_x) * kTileSize;
  const int x1 = std::min(s->width, x0 + kTileSize), y1 = std::min(s->height, y0 + kTileSize);
  alignas(64) float trans[kTilePixels], t_final[kTilePixels], sd[kTilePixels], d_r[kTilePixels], d_g[kTilePixels],
      d_b[kTilePixels], bg_dot[kTilePixels];
  alignas(64) int32_t last[kTilePixels];
  for (int p = 0; p < kTilePixels; ++p) {
    trans[p] = t_final[p] = 1.f;
    sd[p] = d_r[p] = d_g[p] = d_b[p] = bg_dot[p] = 0.f;
    last[p] = 0;  // outside the image: no contributor, never replayed
  }
  const std::array<float, 3>& bg = settings.background;
  int32_t kmax = 0;
  // Per tile row, the largest contributor count: entries at or past it change no pixel of the row
  // and add only zeros to the sums, so the row is skipped with the same bits.
  int32_t row_last[kTileSize] = {};
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const int p = (y - y0) * kTileSize + (x - x0);
      const int64_t pix = int64_t(y) * s->width + x;
      trans[p] = t_final[p] = s->final_transmittance[pix];
      last[p] = s->n_contrib[pix];
      kmax = std::max(kmax, last[p]);
      row_last[y - y0] = std::max(row_last[y - y0], last[p]);
      d_r[p] = v_image[pix * 3];
      d_g[p] = v_image[pix * 3 + 1];
      d_b[p] = v_image[pix * 3 + 2];
      bg_dot[p] = bg[0] * d_r[p] + bg[1] * d_g[p] + bg[2] * d_b[p];
    }
  const int64_t begin = s->tile_offset[t], end = s->tile_offset[t + 1];
  // Each entry's 9 sums go to its slot in the per-Gaussian order (entry_slot), which the reduction
  // then reads sequentially; entries that are not replayed get zeros.
  auto slot = [&](int64_t k) { return &s->entry_grad[int64_t(s->entry_slot[begin + k]) * kEntryGrads]; };
  for (int64_t k = kmax; k < end - begin; ++k) std::fill_n(slot(k), kEntryGrads, 0.f);
  const vf lane_center = lane_centers<W>(x0);
  const vf zero = splat<vf>(0.f), alpha_max = splat<vf>(float(kAlphaMax));
  constexpr int32_t kPrefetch = 8;
  for (int32_t k = kmax - 1; k >= 0; --k) {
    if (k >= kPrefetch) __builtin_prefetch(&s->splat[int64_t(s->tile_gaussian[begin + k - kPrefetch]) * kSplatFloats]);
    const float* sp = &s->splat[int64_t(s->tile_gaussian[begin + k]) * kSplatFloats];
    int px0, px1, py0, py1;
    box_in_tile(sp, x0, x1, y0, y1, &px0, &px1, &py0, &py1);
    if (px0 > px1 || py0 > py1) {
      std::fill_n(slot(k), kEntryGrads, 0.f);
      continue;
    }
    const vf mx = splat<vf>(sp[0]), ca = splat<vf>(sp[2]), cb = splat<vf>(sp[3]), cc = splat<vf>(sp[4]);
    const vf o = splat<vf>(sp[5]), cr = splat<vf>(sp[6]), cg = splat<vf>(sp[7]), cbl = splat<vf>(sp[8]);
    const vi kv = vi{} + k;
    v8f acc[kSums];
    for (int j = 0; j < kSums; ++j) acc[j] = v8f{};
    // One W-pixel block at column bx of the tile: updates the pixels' state and writes its 9 terms.
    auto block = [&](int p, int bx, vf dy, vf* out) __attribute__((always_inline)) {
      const vf dx = mx - (lane_center + float(bx));
      const vf power = -0.5f * (ca * dx * dx + cc * dy * dy) - cb * dx * dy;
      const vf gauss = blend_exp_v<W>(vmin(power, zero));
      const vf alpha_raw = o * gauss;
      const vf alpha = vmin(alpha_max, alpha_raw);
      const vi ok = (kv < load<vi>(&last[p])) & (power <= 0.f) & (alpha >= float(kAlphaMin));
      const vf inv = 1.f / (1.f - alpha);
      const vf tr = load<vf>(&trans[p]);
      const vf tp = ok ? tr * inv : tr;
      store(&trans[p], tp);
      const vf dr = load<vf>(&d_r[p]), dg = load<vf>(&d_g[p]), db = load<vf>(&d_b[p]);
      const vf cd = cr * dr + cg * dg + cbl * db;
      const vf behind = load<vf>(&sd[p]);
      vf v_alpha = cd * tp - behind * inv;
      if constexpr (kBackground) v_alpha -= load<vf>(&t_final[p]) * inv * load<vf>(&bg_dot[p]);
      const vf wc = ok ? alpha * tp : zero;
      store(&sd[p], behind + cd * wc);
      // A clamped alpha (o G > 0.99) is flat in opacity and position.
      const vf va = (ok & (alpha_raw <= alpha_max)) ? v_alpha : zero;
      const vf v_power = o * va * gauss;
      const vf gx = v_power * dx, gy = v_power * dy;
      out[0] = gx;
      out[1] = gy;
      out[2] = gx * dx;
      out[3] = gx * dy;
      out[4] = gy * dy;
      out[5] = gauss * va;
      out[6] = wc * dr;
      out[7] = wc * dg;
      out[8] = wc * db;
    };
    const float inv_ca = 1.f / sp[2];
    for (int py = py0; py <= py1; ++py) {
      if (k >= row_last[py - y0]) continue;
      // The row's chord of the ellipse (measured: this pays in the backward, where a block costs
      // about twice the forward's; in the forward it cost more than it saved).
      int rx0 = px0, rx1 = px1;
      row_span(sp, inv_ca, py, &rx0, &rx1);
      if (rx0 > rx1) continue;
      const int gx0 = ((rx0 - x0) / 8) * 8, gx1 = rx1 - x0;
      const vf dy = splat<vf>(sp[1] - (float(py) + 0.5f));
      const int row = (py - y0) * kTileSize;
      for (int bx = gx0; bx <= gx1; bx += 8) {
        if constexpr (W == 8) {
          vf g[kSums];
          block(row + bx, bx, dy, g);
          for (int j = 0; j < kSums; ++j) acc[j] += g[j];
        } else {
          vf lo[kSums], hi[kSums];
          block(row + bx, bx, dy, lo);
          block(row + bx + 4, bx + 4, dy, hi);
          for (int j = 0; j < kSums; ++j) acc[j] += __builtin_shufflevector(lo[j], hi[j], 0, 1, 2, 3, 4, 5, 6, 7);
        }
      }
    }
    float sum[kSums];
    for (int j = 0; j < kSums; ++j) {
      const v4f lo = __builtin_shufflevector(acc[j], acc[j], 0, 1, 2, 3);
      const v4f hi = __builtin_shufflevector(acc[j], acc[j], 4, 5, 6, 7);
      sum[j] = hsum4(lo + hi);
    }
    float* eg = slot(k);
    eg[0] = -(sp[2] * sum[0] + sp[3] * sum[1]);
    eg[1] = -(sp[4] * sum[1] + sp[3] * sum[0]);
    eg[2] = -0.5f * sum[2];
    eg[3] = -sum[3];
    eg[4] = -0.5f * sum[4];
    for (int j = 5; j < kSums; ++j) eg[j] = sum[j];
  }
}

bool has_background(const RasterSettings<float>& st) {
  return st.background[0] != 0.f || st.background[1] != 0.f || st.background[2] != 0.f;
}

void render_w4(const RasterSettings<float>& st, RasterState<float>* s, int64_t t) {
  if (st.outputs == RasterOutputs::kTraining) render_tile<4, true>(st, s, t);
  else render_tile<4, false>(st, s, t);  // no FMA in SSE2: the 4-lane render is not fused
}

void backward_w4(const RasterSettings<float>& st, RasterState<float>* s, const std::vector<float>& v, int64_t t) {
  if (has_background(st)) backward_tile<4, true>(st, s, v, t);
  else backward_tile<4, false>(st, s, v, t);
}
#if defined(__x86_64__) && defined(__GNUC__)
#define WGS_WIDE_KERNELS 1
// The image-only render here only for an AVX2 CPU without FMA (fused_image_kernel() false).
__attribute__((target("avx2"))) void render_w8(const RasterSettings<float>& st, RasterState<float>* s, int64_t t) {
  if (st.outputs == RasterOutputs::kTraining) render_tile<8, true>(st, s, t);
  else render_tile<8, false>(st, s, t);
}
__attribute__((target("avx2"))) void backward_w8(const RasterSettings<float>& st, RasterState<float>* s,
                                                 const std::vector<float>& v, int64_t t) {
  if (has_background(st)) backward_tile<8, true>(st, s, v, t);
  else backward_tile<8, false>(st, s, v, t);
}
#endif

bool cpu_supports(int width) {
  if (width == 4) return true;
#ifdef WGS_WIDE_KERNELS
  if (width == 8) return __builtin_cpu_supports("avx2");
#endif
  return false;
}

std::atomic<int>& selected_width() {
  static std::atomic<int> w{[] {
    return cpu_supports(8) ? 8 : 4;
  }()};
  return w;
}

}  // namespace

bool set_tile_kernel_width(int width) {
  if ((width != 4 && width != 8) || !cpu_supports(width)) return false;
  selected_width().store(width);
  return true;
}

int tile_kernel_width() { return selected_width().load(); }

bool fused_image_kernel() {
#ifdef WGS_WIDE_KERNELS
  static const bool has_fma = __builtin_cpu_supports("fma");
  return has_fma && selected_width().load(std::memory_order_relaxed) == 8;
#else
  return false;
#endif
}

void render_tile_simd(const RasterSettings<float>& settings, RasterState<float>* s, int64_t tile) {
  switch (selected_width().load(std::memory_order_relaxed)) {
#ifdef WGS_WIDE_KERNELS
    case 8:
      if (settings.outputs == RasterOutputs::kImage && fused_image_kernel())
        return render_image_tile_fused(settings, s, tile);
      return render_w8(settings, s, tile);
#endif
    default: return render_w4(settings, s, tile);
  }
}

void backward_tile_simd(const RasterSettings<float>& settings, RasterState<float>* s, const std::vector<float>& v_image,
                        int64_t tile) {
  switch (selected_width().load(std::memory_order_relaxed)) {
#ifdef WGS_WIDE_KERNELS
    case 8: return backward_w8(settings, s, v_image, tile);
#endif
    default: return backward_w4(settings, s, v_image, tile);
  }
}

}  // namespace weathergs::reconstruction::internal
