// max_blend_weights (rasterizer.h): the training forward's blend replayed one pixel at a time,
// keeping per tile entry the largest weight instead of the colour.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "core/error.h"
#include "core/parallel.h"
#include "reconstruction/raster_internal.h"

namespace weathergs::reconstruction {

template <typename T>
void max_blend_weights(const RasterState<T>& s, std::vector<T>* weights) {
  using namespace internal;
  const int num_tiles = s.tiles_x * s.tiles_y;
  const int64_t entries = s.num_entries();
  WGS_CHECK_EQ(size_t(entries), s.tile_gaussian.size());
  static thread_local std::vector<T> entry_max_buffer;
  // By reference: a thread_local named inside the lambda would be each worker's own.
  std::vector<T>& entry_max = entry_max_buffer;
  entry_max.assign(size_t(entries), T(0));
  const T alpha_min = T(kAlphaMin), alpha_max = T(kAlphaMax), t_min = T(kTransmittanceMin);
  // The per-pixel arithmetic of the forward's scalar template (rasterizer.cc, render_tiles), which
  // the float SIMD kernels do lane by lane: the same alphas, transmittances and stops.
  parallel_for(0, num_tiles, [&](int64_t t) {
    const int x0 = int(t % s.tiles_x) * kTileSize, y0 = int(t / s.tiles_x) * kTileSize;
    const int x1 = std::min(s.width, x0 + kTileSize), y1 = std::min(s.height, y0 + kTileSize);
    T trans[kTilePixels];
    bool done[kTilePixels];
    std::fill_n(trans, kTilePixels, T(1));
    std::fill_n(done, kTilePixels, false);
    const int64_t npix = int64_t(x1 - x0) * (y1 - y0);
    int64_t num_done = 0;
    const int64_t begin = s.tile_offset[t], end = s.tile_offset[t + 1];
    for (int64_t k = begin; k < end && num_done < npix; ++k) {
      const T* sp = &s.splat[int64_t(s.tile_gaussian[k]) * kSplatFloats];
      const T mx = sp[0], my = sp[1], ca = sp[2], cb = sp[3], cc = sp[4], o = sp[5];
      int px0, px1, py0, py1;
      box_in_tile(sp, x0, x1, y0, y1, &px0, &px1, &py0, &py1);
      T best = T(0);
      for (int py = py0; py <= py1; ++py) {
        const T dy = my - (T(py) + T(0.5));
        const int row = (py - y0) * kTileSize - x0;
        for (int px = px0; px <= px1; ++px) {
          const int p = row + px;
          if (done[p]) continue;
          const T dx = mx - (T(px) + T(0.5));
          const T power = splat_power(ca, cb, cc, dx, dy);
          if (!(power <= T(0))) continue;
          const T alpha = std::min(alpha_max, o * blend_exp(std::min(power, T(0))));
          if (!(alpha >= alpha_min)) continue;
          const T test_t = trans[p] * (T(1) - alpha);
          if (test_t < t_min) {  // the blend stops here: this Gaussian adds nothing to the pixel
            done[p] = true;
            ++num_done;
            continue;
          }
          best = std::max(best, alpha * trans[p]);
          trans[p] = test_t;
        }
      }
      entry_max[size_t(k)] = best;
    }
  });
  weights->assign(s.radius.size(), T(0));
  for (int64_t k = 0; k < entries; ++k) {
    T& w = (*weights)[size_t(s.tile_gaussian[size_t(k)])];
    w = std::max(w, entry_max[size_t(k)]);
  }
}

template void max_blend_weights<float>(const RasterState<float>&, std::vector<float>*);
template void max_blend_weights<double>(const RasterState<double>&, std::vector<double>*);

}  // namespace weathergs::reconstruction
