// The float tile kernels of the rasterizer, 4 pixels at a time with GCC/Clang vector extensions.
#include <algorithm>
#include <cstring>

#include "reconstruction/raster_internal.h"

namespace weathergs::recon::internal {

namespace {
// ---------------------------------------------------------------------------------------------
// float tile kernels, 4 pixels at a time with GCC/Clang vector extensions (portable: SSE2 on
// x86-64, NEON on arm64). They compute exactly what the scalar kernels below compute, lane by lane;
// the lanes of a 4-pixel block that lie outside a Gaussian's alpha extent get alpha < 1/255 and are
// skipped by the same test as any other pixel.

using v4f = float __attribute__((vector_size(16)));
using v4i = int32_t __attribute__((vector_size(16)));

inline v4f splat4(float v) { return v4f{v, v, v, v}; }
inline v4f vmin(v4f a, v4f b) { return a < b ? a : b; }
inline v4f vmax(v4f a, v4f b) { return a > b ? a : b; }
inline v4f load4(const float* p) { v4f v; std::memcpy(&v, p, 16); return v; }
inline void store4(float* p, v4f v) { std::memcpy(p, &v, 16); }
inline v4i load4i(const int32_t* p) { v4i v; std::memcpy(&v, p, 16); return v; }
inline void store4i(int32_t* p, v4i v) { std::memcpy(p, &v, 16); }

// blend_exp(float) on 4 lanes, same operations in the same order.
inline v4f blend_exp4(v4f x) {
  x = vmax(x, splat4(-87.0f));
  const v4f t = x * 1.44269504088896341f;
  const v4i n = __builtin_convertvector(t - 0.5f, v4i);
  const v4f fn = __builtin_convertvector(n, v4f);
  v4f r = x - fn * 0.693359375f;
  r = r - fn * -2.12194440e-4f;
  v4f p = splat4(1.9875691500e-4f);
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  const v4f y = p * r * r + r + 1.0f;
  const v4i bits = (n + 127) << 23;
  v4f scale;
  std::memcpy(&scale, &bits, 16);
  return y * scale;
}

inline float hsum(v4f v) { return ((v[0] + v[1]) + v[2]) + v[3]; }

}  // namespace

void render_tile_simd(const RasterSettings<float>& settings, RasterState<float>* s, int64_t t) {
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
  const int64_t begin = s->tile_offset[t], end = s->tile_offset[t + 1];
  const v4f lane_center = v4f{0.5f, 1.5f, 2.5f, 3.5f} + float(x0);
  constexpr int64_t kPrefetch = 8;  // records are scattered over memory: fetch ahead of use
  for (int64_t k = begin; k < end && num_done < npix; ++k) {
    if (k + kPrefetch < end) __builtin_prefetch(&s->splat_sorted[int64_t(s->tile_rank[k + kPrefetch]) * kSplatFloats]);
    const float* sp = &s->splat_sorted[int64_t(s->tile_rank[k]) * kSplatFloats];
    if (sp[9] < 0.f) continue;
    int px0, px1, py0, py1;
    pixel_range(sp[0], sp[9], x0, x1 - 1, &px0, &px1);
    pixel_range(sp[1], sp[10], y0, y1 - 1, &py0, &py1);
    if (px0 > px1) continue;
    const v4f mx = splat4(sp[0]), ca = splat4(sp[2]), cb = splat4(sp[3]), cc = splat4(sp[4]), o = splat4(sp[5]);
    const v4f r = splat4(sp[6]), g = splat4(sp[7]), b = splat4(sp[8]);
    const v4i contributor = v4i{0, 0, 0, 0} + int32_t(k - begin + 1);
    const int bx0 = ((px0 - x0) / 4) * 4, bx1 = px1 - x0;
    v4i stopped = {0, 0, 0, 0};
    for (int py = py0; py <= py1; ++py) {
      const v4f dy = splat4(sp[1] - (float(py) + 0.5f));
      const int row = (py - y0) * kTileSize;
      for (int bx = bx0; bx <= bx1; bx += 4) {
        const int p = row + bx;
        const v4f dx = mx - (lane_center + float(bx));
        const v4f power = -0.5f * (ca * dx * dx + cc * dy * dy) - cb * dx * dy;
        const v4f alpha = vmin(splat4(float(kAlphaMax)), o * blend_exp4(vmin(power, splat4(0.f))));
        const v4f tp = load4(&trans[p]);
        const v4f test_t = tp * (1.f - alpha);
        const v4i ok = (power <= 0.f) & (alpha >= float(kAlphaMin)) & (load4i(&done[p]) == 0);
        const v4i stop = ok & (test_t < float(kTransmittanceMin));
        const v4i add = ok & ~stop;
        const v4f w = add ? alpha * tp : splat4(0.f);
        store4(&cr[p], load4(&cr[p]) + r * w);
        store4(&cg[p], load4(&cg[p]) + g * w);
        store4(&cb_[p], load4(&cb_[p]) + b * w);
        store4(&trans[p], add ? test_t : tp);
        store4i(&last[p], add ? contributor : load4i(&last[p]));
        store4i(&done[p], load4i(&done[p]) | stop);
        stopped -= stop;
      }
    }
    num_done += stopped[0] + stopped[1] + stopped[2] + stopped[3];
  }
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const int p = (y - y0) * kTileSize + (x - x0);
      const int64_t pix = int64_t(y) * s->width + x;
      s->image[pix * 3] = cr[p] + trans[p] * settings.background[0];
      s->image[pix * 3 + 1] = cg[p] + trans[p] * settings.background[1];
      s->image[pix * 3 + 2] = cb_[p] + trans[p] * settings.background[2];
      s->final_transmittance[pix] = trans[p];
      s->n_contrib[pix] = last[p];
    }
}

void backward_tile_simd(const RasterSettings<float>& settings, RasterState<float>* s, const std::vector<float>& v_image,
                        int64_t t) {
  const int x0 = int(t % s->tiles_x) * kTileSize, y0 = int(t / s->tiles_x) * kTileSize;
  const int x1 = std::min(s->width, x0 + kTileSize), y1 = std::min(s->height, y0 + kTileSize);
  alignas(64) float trans[kTilePixels], t_final[kTilePixels], acc_r[kTilePixels], acc_g[kTilePixels],
      acc_b[kTilePixels], last_r[kTilePixels], last_g[kTilePixels], last_b[kTilePixels], last_alpha[kTilePixels],
      d_r[kTilePixels], d_g[kTilePixels], d_b[kTilePixels], bg_dot[kTilePixels];
  alignas(64) int32_t last[kTilePixels];
  for (int p = 0; p < kTilePixels; ++p) {
    trans[p] = t_final[p] = 1.f;
    acc_r[p] = acc_g[p] = acc_b[p] = last_r[p] = last_g[p] = last_b[p] = last_alpha[p] = 0.f;
    d_r[p] = d_g[p] = d_b[p] = bg_dot[p] = 0.f;
    last[p] = 0;  // outside the image: no contributor, never replayed
  }
  const std::array<float, 3>& bg = settings.background;
  int32_t kmax = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const int p = (y - y0) * kTileSize + (x - x0);
      const int64_t pix = int64_t(y) * s->width + x;
      trans[p] = t_final[p] = s->final_transmittance[pix];
      last[p] = s->n_contrib[pix];
      kmax = std::max(kmax, last[p]);
      d_r[p] = v_image[pix * 3];
      d_g[p] = v_image[pix * 3 + 1];
      d_b[p] = v_image[pix * 3 + 2];
      bg_dot[p] = bg[0] * d_r[p] + bg[1] * d_g[p] + bg[2] * d_b[p];
    }
  const int64_t begin = s->tile_offset[t], end = s->tile_offset[t + 1];
  std::fill(s->entry_grad.begin() + begin * kEntryGrads, s->entry_grad.begin() + end * kEntryGrads, 0.f);
  const v4f lane_center = v4f{0.5f, 1.5f, 2.5f, 3.5f} + float(x0);
  const v4f zero = splat4(0.f), alpha_max = splat4(float(kAlphaMax));
  constexpr int32_t kPrefetch = 8;
  for (int32_t k = kmax - 1; k >= 0; --k) {
    if (k >= kPrefetch) __builtin_prefetch(&s->splat_sorted[int64_t(s->tile_rank[begin + k - kPrefetch]) * kSplatFloats]);
    const float* sp = &s->splat_sorted[int64_t(s->tile_rank[begin + k]) * kSplatFloats];
    if (sp[9] < 0.f) continue;
    int px0, px1, py0, py1;
    pixel_range(sp[0], sp[9], x0, x1 - 1, &px0, &px1);
    pixel_range(sp[1], sp[10], y0, y1 - 1, &py0, &py1);
    if (px0 > px1 || py0 > py1) continue;
    const v4f mx = splat4(sp[0]), ca = splat4(sp[2]), cb = splat4(sp[3]), cc = splat4(sp[4]), o = splat4(sp[5]);
    const v4f cr = splat4(sp[6]), cg = splat4(sp[7]), cbl = splat4(sp[8]);
    const v4i kv = v4i{0, 0, 0, 0} + k;
    v4f g_mx = zero, g_my = zero, g_a = zero, g_b = zero, g_c = zero, g_o = zero, g_r = zero, g_g = zero, g_bl = zero;
    const int bx0 = ((px0 - x0) / 4) * 4, bx1 = px1 - x0;
    for (int py = py0; py <= py1; ++py) {
      const v4f dy = splat4(sp[1] - (float(py) + 0.5f));
      const int row = (py - y0) * kTileSize;
      for (int bx = bx0; bx <= bx1; bx += 4) {
        const int p = row + bx;
        const v4f dx = mx - (lane_center + float(bx));
        const v4f power = -0.5f * (ca * dx * dx + cc * dy * dy) - cb * dx * dy;
        const v4f gauss = blend_exp4(vmin(power, zero));
        const v4f alpha_raw = o * gauss;
        const v4f alpha = vmin(alpha_max, alpha_raw);
        const v4i ok = (kv < load4i(&last[p])) & (power <= 0.f) & (alpha >= float(kAlphaMin));
        const v4f one_minus = 1.f - alpha;
        const v4f tr = load4(&trans[p]);
        const v4f tp = ok ? tr / one_minus : tr;
        store4(&trans[p], tp);
        const v4f w = alpha * tp;
        const v4f la = load4(&last_alpha[p]);
        const v4f ar = la * load4(&last_r[p]) + (1.f - la) * load4(&acc_r[p]);
        const v4f ag = la * load4(&last_g[p]) + (1.f - la) * load4(&acc_g[p]);
        const v4f ab = la * load4(&last_b[p]) + (1.f - la) * load4(&acc_b[p]);
        const v4f dr = load4(&d_r[p]), dg = load4(&d_g[p]), db = load4(&d_b[p]);
        v4f v_alpha = ((cr - ar) * dr + (cg - ag) * dg + (cbl - ab) * db) * tp;
        v_alpha += -load4(&t_final[p]) / one_minus * load4(&bg_dot[p]);
        store4(&acc_r[p], ok ? ar : load4(&acc_r[p]));
        store4(&acc_g[p], ok ? ag : load4(&acc_g[p]));
        store4(&acc_b[p], ok ? ab : load4(&acc_b[p]));
        store4(&last_r[p], ok ? cr : load4(&last_r[p]));
        store4(&last_g[p], ok ? cg : load4(&last_g[p]));
        store4(&last_b[p], ok ? cbl : load4(&last_b[p]));
        store4(&last_alpha[p], ok ? alpha : la);
        const v4f wc = ok ? w : zero;
        g_r += wc * dr;
        g_g += wc * dg;
        g_bl += wc * db;
        const v4f va = (ok & (alpha_raw <= alpha_max)) ? v_alpha : zero;
        const v4f v_power = o * va * gauss;
        g_mx += v_power * -(ca * dx + cb * dy);
        g_my += v_power * -(cc * dy + cb * dx);
        g_a += v_power * -0.5f * dx * dx;
        g_b += v_power * -dx * dy;
        g_c += v_power * -0.5f * dy * dy;
        g_o += gauss * va;
      }
    }
    float* eg = &s->entry_grad[(begin + k) * kEntryGrads];
    eg[0] = hsum(g_mx); eg[1] = hsum(g_my); eg[2] = hsum(g_a); eg[3] = hsum(g_b); eg[4] = hsum(g_c);
    eg[5] = hsum(g_o); eg[6] = hsum(g_r); eg[7] = hsum(g_g); eg[8] = hsum(g_bl);
  }
}

}  // namespace weathergs::recon::internal
