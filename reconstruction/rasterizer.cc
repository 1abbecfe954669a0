#include "reconstruction/rasterizer.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "core/error.h"
#include "core/parallel.h"
#include "reconstruction/raster_internal.h"

namespace weathergs::reconstruction {

namespace {

using namespace internal;
template <typename T>
void preprocess(const GaussianSet<T>& g, const RasterCamera<T>& cam, const RasterSettings<T>& settings,
                RasterState<T>* s) {
  const int64_t n = int64_t(g.size());
  parallel_for_chunks(0, n, kGaussianChunk, [&](int64_t, int64_t lo, int64_t hi) {
    for (int64_t i = lo; i < hi; ++i) {
      clear_gaussian(s, i);
      const Vec3<T> p(g.position[i * 3], g.position[i * 3 + 1], g.position[i * 3 + 2]);
      const T z = cam.rotation.row(2).dot(p) + cam.translation.z();
      if (!(z > T(kNearPlane))) continue;  // also culls NaN
      const Vec3<T> ls(g.log_scale[i * 3], g.log_scale[i * 3 + 1], g.log_scale[i * 3 + 2]);
      const Vec4<T> q(g.rotation[i * 4], g.rotation[i * 4 + 1], g.rotation[i * 4 + 2], g.rotation[i * 4 + 3]);
      const Vec3<T> scale = scale_from_log(ls);
      for (int k = 0; k < 3; ++k) s->scale[i * 3 + k] = scale[k];
      const Mat3<T> sigma = covariance_3d_from_scale(scale, q);
      const Projection<T> pr = project_gaussian(p, sigma, cam);
      T len;
      const Vec3<T> dir = view_direction(p, cam.center_world, &len);
      bool clamped[3];
      const Vec3<T> color = sh_to_color(settings.sh_degree, &g.sh[i * kShFloats], dir, clamped);
      const T rgb[3] = {color.x(), color.y(), color.z()};
      finish_gaussian(s, i, pr.mean.x(), pr.mean.y(), pr.cov(0, 0), pr.cov(0, 1), pr.cov(1, 1), z, rgb,
                      uint8_t((clamped[0] ? 1 : 0) | (clamped[1] ? 2 : 0) | (clamped[2] ? 4 : 0)),
                      g.opacity_logit[i]);
    }
  });
}

template <typename T>
inline int64_t num_tile_entries(const RasterState<T>& s, int64_t i) {
  const int32_t* r = &s.rect[i * 4];
  const int64_t area = s.radius[i] > 0 ? int64_t(r[2] - r[0]) * (r[3] - r[1]) : 0;
  if (area == 0 || area > kMaskTiles) return area;
  return __builtin_popcountll(s.tile_mask[i]);
}

// Sorts the (depth bits << 32 | index) keys, which arrive in increasing index order: a stable LSD
// radix sort on the 32 depth bits (three passes of 11 bits) keeps that order among equal depths, so
// the result is exactly std::sort's of the 64-bit keys, in linear time. Each pass counts per chunk
// of the input and scatters each chunk from its own starts (buckets in order, chunks in order within
// a bucket): the serial stable pass's result, whatever the thread count. A pass whose digit is the
// same for every key would not move anything and is skipped.
inline void sort_by_depth(std::vector<uint64_t>* keys) {
  constexpr int kBits = 11, kBuckets = 1 << kBits;
  constexpr int64_t kSortChunk = 8192;
  static thread_local std::vector<uint64_t> tmp_buffer;
  static thread_local std::vector<int64_t> start_buffer;
  // By reference: a thread_local named inside the lambdas would be each worker's own.
  std::vector<uint64_t>& tmp = tmp_buffer;
  std::vector<int64_t>& start = start_buffer;
  const int64_t n = int64_t(keys->size());
  const int64_t chunks = num_chunks(0, n, kSortChunk);
  tmp.resize(size_t(n));
  start.resize(size_t(chunks) * kBuckets);
  uint64_t* src = keys->data();
  uint64_t* dst = tmp.data();
  for (int pass = 0; pass < 3; ++pass) {
    const int shift = 32 + pass * kBits;
    auto digit = [shift](uint64_t key) { return int((key >> shift) & (kBuckets - 1)); };
    parallel_for_chunks(0, n, kSortChunk, [&](int64_t c, int64_t lo, int64_t hi) {
      int64_t* count = &start[size_t(c) * kBuckets];
      std::fill_n(count, kBuckets, 0);
      for (int64_t i = lo; i < hi; ++i) ++count[digit(src[i])];
    });
    int64_t run = 0;
    bool one_bucket = false;
    for (int b = 0; b < kBuckets; ++b) {
      const int64_t bucket_begin = run;
      for (int64_t c = 0; c < chunks; ++c) {
        const int64_t count = start[size_t(c) * kBuckets + b];
        start[size_t(c) * kBuckets + b] = run;
        run += count;
      }
      one_bucket |= run - bucket_begin == n;
    }
    if (one_bucket) continue;
    parallel_for_chunks(0, n, kSortChunk, [&](int64_t c, int64_t lo, int64_t hi) {
      int64_t* cursor = &start[size_t(c) * kBuckets];
      for (int64_t i = lo; i < hi; ++i) dst[cursor[digit(src[i])]++] = src[i];
    });
    std::swap(src, dst);
  }
  if (src != keys->data()) keys->swap(tmp);
}

// Builds the per-tile depth-sorted lists and, per Gaussian, the entries of its tiles. One global
// sort of the visible Gaussians by (depth, index), then a scatter in that order: every tile list
// comes out sorted exactly as a per-tile sort would leave it. The lists hold Gaussian indices and the
// kernels read the records where preprocessing wrote them: gathering the records into depth order
// cost more in the scatter than it saved in the blend (benchmarks/README.md).
template <typename T>
void bin_and_sort(RasterState<T>* s, std::vector<uint64_t>* keys, bool entry_slots) {
  const int64_t n = int64_t(s->radius.size());
  const int num_tiles = s->tiles_x * s->tiles_y;
  // Entry offsets and the visible Gaussians' keys in index order, in two parallel passes over
  // chunks: counts per chunk, then each chunk writes from its prefix.
  s->entry_offset.resize(n + 1);
  s->entry_offset[0] = 0;
  const int64_t gaussian_chunks = num_chunks(0, n, kGaussianChunk);
  static thread_local std::vector<int64_t> chunk_sums_buffer;
  std::vector<int64_t>& chunk_sums = chunk_sums_buffer;  // entries, visible Gaussians per chunk
  chunk_sums.assign(size_t(gaussian_chunks + 1) * 2, 0);
  parallel_for_chunks(0, n, kGaussianChunk, [&](int64_t c, int64_t lo, int64_t hi) {
    int64_t entries = 0, visible = 0;
    for (int64_t i = lo; i < hi; ++i) {
      const int64_t count = num_tile_entries(*s, i);
      s->entry_offset[i + 1] = count;  // the count for now, the offset below
      entries += count;
      visible += count > 0;
    }
    chunk_sums[size_t(c + 1) * 2] = entries;
    chunk_sums[size_t(c + 1) * 2 + 1] = visible;
  });
  for (int64_t c = 0; c < gaussian_chunks; ++c) {
    chunk_sums[size_t(c + 1) * 2] += chunk_sums[size_t(c) * 2];
    chunk_sums[size_t(c + 1) * 2 + 1] += chunk_sums[size_t(c) * 2 + 1];
  }
  keys->resize(size_t(chunk_sums[size_t(gaussian_chunks) * 2 + 1]));
  parallel_for_chunks(0, n, kGaussianChunk, [&](int64_t c, int64_t lo, int64_t hi) {
    int64_t offset = chunk_sums[size_t(c) * 2], slot = chunk_sums[size_t(c) * 2 + 1];
    for (int64_t i = lo; i < hi; ++i) {
      const int64_t count = s->entry_offset[i + 1];
      s->entry_offset[i + 1] = offset += count;
      if (count == 0) continue;
      // Depth is > 0.2, so the float bit pattern orders like the value; ties go to the lower index.
      const float d = float(s->depth[i]);
      uint32_t bits;
      std::memcpy(&bits, &d, 4);
      (*keys)[size_t(slot++)] = (uint64_t(bits) << 32) | uint64_t(uint32_t(i));
    }
  });
  sort_by_depth(keys);
  const int64_t visible = int64_t(keys->size());
  const int64_t entries = s->entry_offset[n];
  // Tile lists in two parallel passes over chunks of the depth order: each chunk counts its entries
  // per tile, the counts become per-(chunk, tile) start positions (tile by tile, chunks in order),
  // and each chunk scatters its Gaussians in depth order from its own starts: the same lists as one
  // serial scatter in depth order, whatever the thread count.
  // A rectangle of at most kMaskTiles tiles visits its mask's set bits (row-major, so the same
  // tiles in the same order as the loops below): one loop whose trip count is the entry count
  // instead of a loop per row and a test per tile (fewer mispredicted branches).
  // The arrays by plain pointer: the passes below write through other pointers, which the compiler
  // cannot tell from the vectors' own members, so it would reload those on every iteration.
  const int32_t* const rects = s->rect.data();
  const uint64_t* const masks = s->tile_mask.data();
  const uint64_t* const sorted = keys->data();
  const int tiles_x = s->tiles_x;
  auto for_each_tile = [rects, masks, tiles_x](int32_t gi, auto&& fn) __attribute__((always_inline)) {
    const int32_t* r = &rects[int64_t(gi) * 4];
    const int w = r[2] - r[0], area = w * (r[3] - r[1]);
    if (area <= kMaskTiles) {
      for (uint64_t m = masks[gi]; m != 0; m &= m - 1) {
        const int b = __builtin_ctzll(m);
        fn((r[1] + b / w) * tiles_x + r[0] + b % w);
      }
      return;
    }
    for (int ty = r[1]; ty < r[3]; ++ty)
      for (int tx = r[0]; tx < r[2]; ++tx) fn(ty * tiles_x + tx);
  };
  // Both passes below visit the Gaussians in depth order, i.e. at random: they fetch what
  // for_each_tile (and the scatter's slots) read 16 ranks ahead.
  auto gaussian_at = [sorted](int64_t rank) __attribute__((always_inline)) {
    return int32_t(sorted[rank] & 0xffffffffu);
  };
  const int64_t* const offsets_of = s->entry_offset.data();
  auto prefetch_ahead = [&](int64_t rank, int64_t hi, auto offsets) __attribute__((always_inline)) {
    constexpr int64_t kPrefetch = 16;
    if (rank + kPrefetch >= hi) return;
    const int64_t ahead = gaussian_at(rank + kPrefetch);
    __builtin_prefetch(&rects[ahead * 4]);
    __builtin_prefetch(&masks[ahead]);
    if constexpr (decltype(offsets)::value) __builtin_prefetch(&offsets_of[ahead]);
  };
  const int64_t chunks = num_chunks(0, visible, kGaussianChunk);
  // The caller's buffer, by reference: a thread_local named inside the lambdas would be each worker's own.
  static thread_local std::vector<int64_t> start_buffer;
  std::vector<int64_t>& start = start_buffer;
  start.assign(size_t(chunks) * num_tiles, 0);
  parallel_for_chunks(0, visible, kGaussianChunk, [&](int64_t c, int64_t lo, int64_t hi) {
    int64_t* count = &start[size_t(c) * num_tiles];
    for (int64_t rank = lo; rank < hi; ++rank) {
      prefetch_ahead(rank, hi, std::false_type{});
      for_each_tile(gaussian_at(rank), [&](int t) __attribute__((always_inline)) { ++count[t]; });
    }
  });
  s->tile_offset.assign(num_tiles + 1, 0);
  for (int t = 0; t < num_tiles; ++t) {
    int64_t run = s->tile_offset[t];
    for (int64_t c = 0; c < chunks; ++c) {
      const int64_t count = start[size_t(c) * num_tiles + t];
      start[size_t(c) * num_tiles + t] = run;
      run += count;
    }
    s->tile_offset[t + 1] = run;
  }
  // Slots and ranks are int32 (half the scatter's writes of int64): checked, not assumed.
  WGS_CHECK_LT(entries, int64_t(std::numeric_limits<int32_t>::max()));
  s->tile_gaussian.resize(entries);
  if (entry_slots) s->entry_slot.resize(entries);
  // The same pass gives each entry its slot in the per-Gaussian order (the Gaussian's tiles in
  // row-major order: entry_slot), which only the backward pass reads.
  int32_t* const lists = s->tile_gaussian.data();
  int32_t* const slots = entry_slots ? s->entry_slot.data() : nullptr;
  auto scatter = [&](auto with_slots) {
    constexpr bool kSlots = decltype(with_slots)::value;
    parallel_for_chunks(0, visible, kGaussianChunk, [&](int64_t c, int64_t lo, int64_t hi) {
      int64_t* cursor = &start[size_t(c) * num_tiles];
      for (int64_t rank = lo; rank < hi; ++rank) {
        prefetch_ahead(rank, hi, with_slots);
        const int32_t gi = gaussian_at(rank);
        [[maybe_unused]] int32_t j = kSlots ? int32_t(offsets_of[gi]) : 0;
        for_each_tile(gi, [&](int t) __attribute__((always_inline)) {
          const int64_t k = cursor[t]++;
          lists[k] = gi;
          if constexpr (kSlots) slots[k] = j++;
        });
      }
    });
  };
  if (entry_slots) scatter(std::true_type{});
  else scatter(std::false_type{});
}


template <typename T>
void render_tiles(const RasterSettings<T>& settings, RasterState<T>* s) {
  const int num_tiles = s->tiles_x * s->tiles_y;
  parallel_for(0, num_tiles, [&](int64_t t) {
    if constexpr (std::is_same_v<T, float>) {
      render_tile_simd(settings, s, t);
      return;
    }
    const int x0 = int(t % s->tiles_x) * kTileSize, y0 = int(t / s->tiles_x) * kTileSize;
    const int x1 = std::min(s->width, x0 + kTileSize), y1 = std::min(s->height, y0 + kTileSize);
    // Per-pixel state in planar arrays, indexed (y - y0) * 16 + (x - x0), so that the inner loop
    // over a row is branch-free and vectorizes.
    alignas(64) T trans[kTilePixels], cr[kTilePixels], cg[kTilePixels], cb_[kTilePixels];
    alignas(64) int32_t last[kTilePixels], done[kTilePixels];
    for (int p = 0; p < kTilePixels; ++p) {
      trans[p] = T(1);
      cr[p] = cg[p] = cb_[p] = T(0);
      last[p] = 0;
      done[p] = 0;
    }
    const int64_t npix = int64_t(x1 - x0) * (y1 - y0);
    int64_t num_done = 0;
    const int64_t begin = s->tile_offset[t], end = s->tile_offset[t + 1];
    const T alpha_min = T(kAlphaMin), alpha_max = T(kAlphaMax), t_min = T(kTransmittanceMin);
    for (int64_t k = begin; k < end && num_done < npix; ++k) {
      const T* sp = &s->splat[int64_t(s->tile_gaussian[k]) * kSplatFloats];
      const T mx = sp[0], my = sp[1], ca = sp[2], cb = sp[3], cc = sp[4], o = sp[5];
      const T r = sp[6], g = sp[7], b = sp[8];
      int px0, px1, py0, py1;
      box_in_tile(sp, x0, x1, y0, y1, &px0, &px1, &py0, &py1);
      const int32_t contributor = int32_t(k - begin + 1);
      int32_t stopped = 0;
      for (int py = py0; py <= py1; ++py) {
        const T dy = my - (T(py) + T(0.5));
        const int row = (py - y0) * kTileSize - x0;
        for (int px = px0; px <= px1; ++px) {
          const int p = row + px;
          const T dx = mx - (T(px) + T(0.5));
          const T power = splat_power(ca, cb, cc, dx, dy);
          const T alpha = std::min(alpha_max, o * blend_exp(std::min(power, T(0))));
          const T tp = trans[p];
          const T test_t = tp * (T(1) - alpha);
          const bool ok = (power <= T(0)) & (alpha >= alpha_min) & (done[p] == 0);
          const bool stop = ok & (test_t < t_min);
          const bool add = ok & !stop;
          const T w = add ? alpha * tp : T(0);
          cr[p] += r * w;
          cg[p] += g * w;
          cb_[p] += b * w;
          trans[p] = add ? test_t : tp;
          last[p] = add ? contributor : last[p];
          done[p] = stop ? 1 : done[p];
          stopped += stop ? 1 : 0;
        }
      }
      num_done += stopped;
    }
    write_tile<true>(settings, s, x0, y0, x1, y1, cr, cg, cb_, trans, last);
  });
}

}  // namespace

template <typename T>
void rasterize_forward(const GaussianSet<T>& g, const RasterCamera<T>& camera, const RasterSettings<T>& settings,
                       RasterState<T>* s) {
  WGS_CHECK(settings.sh_degree >= 0 && settings.sh_degree <= kMaxShDegree);
  WGS_CHECK_EQ(g.sh.size(), g.size() * kShFloats);
  WGS_CHECK_LT(g.size(), size_t(std::numeric_limits<int32_t>::max()));
  WGS_CHECK(camera.width > 0 && camera.height > 0);
  const size_t n = g.size();
  s->width = camera.width;
  s->height = camera.height;
  s->tiles_x = (camera.width + kTileSize - 1) / kTileSize;
  s->tiles_y = (camera.height + kTileSize - 1) / kTileSize;
  s->mean2d.resize(n * 2);
  s->cov2d.resize(n * 3);
  s->conic.resize(n * 3);
  s->opacity.resize(n);
  s->color.resize(n * 3);
  s->scale.resize(n * 3);
  s->depth.resize(n);
  s->radius.resize(n);
  s->rect.resize(n * 4);
  s->tile_mask.resize(n);
  s->clamped.resize(n);
  s->splat.resize(n * kSplatFloats);
  const size_t pixels = size_t(camera.width) * camera.height;
  s->image.resize(pixels * 3);
  s->final_transmittance.resize(pixels);
  s->n_contrib.resize(pixels);
  if constexpr (std::is_same_v<T, float>) preprocess_simd(g, camera, settings, s);
  else preprocess(g, camera, settings, s);
  s->outputs = settings.outputs;
  static thread_local std::vector<uint64_t> keys;
  bin_and_sort(s, &keys, settings.outputs == RasterOutputs::kTraining);
  render_tiles(settings, s);
}

template <typename T>
void rasterize_backward(const GaussianSet<T>& g, const RasterCamera<T>& cam, const RasterSettings<T>& settings,
                        RasterState<T>* s, const std::vector<T>& v_image, GaussianSet<T>* grad,
                        std::vector<T>* v_mean2d_ndc) {
  const int64_t n = int64_t(g.size());
  WGS_CHECK(s->outputs == RasterOutputs::kTraining);  // an image-only forward lacks what this reads
  WGS_CHECK_EQ(size_t(n), s->radius.size());
  WGS_CHECK_EQ(v_image.size(), s->image.size());
  const int num_tiles = s->tiles_x * s->tiles_y;
  s->entry_grad.resize(size_t(s->num_entries()) * kEntryGrads);
  const T alpha_min = T(kAlphaMin), alpha_max = T(kAlphaMax);
  const std::array<T, 3> bg = settings.background;

  // 1. Per tile: replay each pixel's blend back to front, one gradient slot per entry. The float
  // kernels (raster_simd.cc, backward_tile) hold the derivation; this is the same arithmetic one pixel
  // at a time (it serves double, for the finite-difference tests), with per-entry sums in row-major
  // pixel order.
  parallel_for(0, num_tiles, [&](int64_t t) {
    if constexpr (std::is_same_v<T, float>) {
      backward_tile_simd(settings, s, v_image, t);
      return;
    }
    const int x0 = int(t % s->tiles_x) * kTileSize, y0 = int(t / s->tiles_x) * kTileSize;
    const int x1 = std::min(s->width, x0 + kTileSize), y1 = std::min(s->height, y0 + kTileSize);
    alignas(64) T trans[kTilePixels], t_final[kTilePixels], sd[kTilePixels], d_r[kTilePixels], d_g[kTilePixels],
        d_b[kTilePixels], bg_dot[kTilePixels];
    alignas(64) int32_t last[kTilePixels];
    int32_t kmax = 0;
    for (int p = 0; p < kTilePixels; ++p) {
      trans[p] = t_final[p] = T(1);
      sd[p] = d_r[p] = d_g[p] = d_b[p] = bg_dot[p] = T(0);
      last[p] = 0;
    }
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
    // Sums go to each entry's slot in the per-Gaussian order; entries not replayed get zeros.
    auto slot = [&](int64_t k) { return &s->entry_grad[int64_t(s->entry_slot[begin + k]) * kEntryGrads]; };
    for (int64_t k = kmax; k < end - begin; ++k) std::fill_n(slot(k), kEntryGrads, T(0));
    for (int32_t k = kmax - 1; k >= 0; --k) {
      const T* sp = &s->splat[int64_t(s->tile_gaussian[begin + k]) * kSplatFloats];
      int px0, px1, py0, py1;  // the box is empty where alpha never reaches 1/255 (sp[9] < 0)
      box_in_tile(sp, x0, x1, y0, y1, &px0, &px1, &py0, &py1);
      if (px0 > px1 || py0 > py1) {
        std::fill_n(slot(k), kEntryGrads, T(0));
        continue;
      }
      const T mx = sp[0], my = sp[1], ca = sp[2], cb = sp[3], cc = sp[4], o = sp[5];
      const T cr = sp[6], cg = sp[7], cbl = sp[8];
      T sum[kEntryGrads] = {};
      for (int py = py0; py <= py1; ++py) {
        const T dy = my - (T(py) + T(0.5));
        const int row = (py - y0) * kTileSize - x0;
        for (int px = px0; px <= px1; ++px) {
          const int p = row + px;
          const T dx = mx - (T(px) + T(0.5));
          const T power = splat_power(ca, cb, cc, dx, dy);
          const T gauss = blend_exp(std::min(power, T(0)));
          const T alpha_raw = o * gauss;
          const T alpha = std::min(alpha_max, alpha_raw);
          const bool ok = (k < last[p]) & (power <= T(0)) & (alpha >= alpha_min);
          if (!ok) continue;
          const T inv = T(1) / (T(1) - alpha);
          const T tp = trans[p] * inv;
          trans[p] = tp;
          const T cd = cr * d_r[p] + cg * d_g[p] + cbl * d_b[p];
          T v_alpha = cd * tp - sd[p] * inv;
          v_alpha -= t_final[p] * inv * bg_dot[p];
          const T w = alpha * tp;
          sd[p] += cd * w;
          // A clamped alpha (o G > 0.99) is flat in opacity and position.
          const T va = alpha_raw <= alpha_max ? v_alpha : T(0);
          const T v_power = o * va * gauss;
          sum[0] += v_power * dx;
          sum[1] += v_power * dy;
          sum[2] += v_power * dx * dx;
          sum[3] += v_power * dx * dy;
          sum[4] += v_power * dy * dy;
          sum[5] += gauss * va;
          sum[6] += w * d_r[p];
          sum[7] += w * d_g[p];
          sum[8] += w * d_b[p];
        }
      }
      T* eg = slot(k);
      eg[0] = -(ca * sum[0] + cb * sum[1]);
      eg[1] = -(cc * sum[1] + cb * sum[0]);
      eg[2] = T(-0.5) * sum[2];
      eg[3] = -sum[3];
      eg[4] = T(-0.5) * sum[4];
      for (int j = 5; j < kEntryGrads; ++j) eg[j] = sum[j];
    }
  });

  // 2. Per Gaussian: sum its entries in tile order, then pull back to the parameters.
  // Sized here and zeroed per Gaussian in the parallel loop below (one pass over the memory instead
  // of a serial fill first): every element is written for every Gaussian.
  grad->position.resize(size_t(n) * 3);
  grad->log_scale.resize(size_t(n) * 3);
  grad->rotation.resize(size_t(n) * 4);
  grad->opacity_logit.resize(size_t(n));
  grad->sh.resize(size_t(n) * kShFloats);
  if (v_mean2d_ndc) v_mean2d_ndc->resize(size_t(n) * 2);
  const T ndc_x = T(0.5) * T(s->width), ndc_y = T(0.5) * T(s->height);
  parallel_for_chunks(0, n, kGaussianChunk, [&](int64_t, int64_t lo, int64_t hi) {
    for (int64_t i = lo; i < hi; ++i) {
      std::fill_n(&grad->sh[i * kShFloats], kShFloats, T(0));  // sh_to_color_vjp accumulates
      if (s->radius[i] == 0) {
        std::fill_n(&grad->position[i * 3], 3, T(0));
        std::fill_n(&grad->log_scale[i * 3], 3, T(0));
        std::fill_n(&grad->rotation[i * 4], 4, T(0));
        grad->opacity_logit[i] = T(0);
        if (v_mean2d_ndc) (*v_mean2d_ndc)[i * 2] = (*v_mean2d_ndc)[i * 2 + 1] = T(0);
        continue;
      }
      T eg[kEntryGrads] = {0, 0, 0, 0, 0, 0, 0, 0, 0};
      for (int64_t j = s->entry_offset[i]; j < s->entry_offset[i + 1]; ++j) {
        const T* e = &s->entry_grad[j * kEntryGrads];
        for (int k = 0; k < kEntryGrads; ++k) eg[k] += e[k];
      }
      if (v_mean2d_ndc) {
        (*v_mean2d_ndc)[i * 2] = eg[0] * ndc_x;
        (*v_mean2d_ndc)[i * 2 + 1] = eg[1] * ndc_y;
      }
      const T o = s->opacity[i];
      grad->opacity_logit[i] = eg[5] * o * (T(1) - o);
      const Vec3<T> p(g.position[i * 3], g.position[i * 3 + 1], g.position[i * 3 + 2]);
      // The forward pass's scales: the same values as scale_from_log(log_scale), without its exps.
      const Vec3<T> scale(s->scale[i * 3], s->scale[i * 3 + 1], s->scale[i * 3 + 2]);
      const Vec4<T> q(g.rotation[i * 4], g.rotation[i * 4 + 1], g.rotation[i * 4 + 2], g.rotation[i * 4 + 3]);
      Mat2<T> cov;
      cov << s->cov2d[i * 3], s->cov2d[i * 3 + 1], s->cov2d[i * 3 + 1], s->cov2d[i * 3 + 2];
      const Mat2<T> v_cov = inverse_2x2_vjp(cov, Vec3<T>(eg[2], eg[3], eg[4]));
      const Mat3<T> sigma = covariance_3d_from_scale(scale, q);
      Vec3<T> v_p = Vec3<T>::Zero();
      Mat3<T> v_sigma = Mat3<T>::Zero();
      project_gaussian_vjp(p, sigma, cam, Vec2<T>(eg[0], eg[1]), v_cov, &v_p, &v_sigma);
      Vec3<T> v_ls = Vec3<T>::Zero();
      Vec4<T> v_q = Vec4<T>::Zero();
      covariance_3d_vjp_from_scale(scale, q, v_sigma, &v_ls, &v_q);
      const bool clamped[3] = {(s->clamped[i] & 1) != 0, (s->clamped[i] & 2) != 0, (s->clamped[i] & 4) != 0};
      sh_to_color_vjp(settings.sh_degree, &g.sh[i * kShFloats], p, cam.center_world, Vec3<T>(eg[6], eg[7], eg[8]),
                      clamped, &grad->sh[i * kShFloats], &v_p);
      for (int k = 0; k < 3; ++k) {
        grad->position[i * 3 + k] = v_p[k];
        grad->log_scale[i * 3 + k] = v_ls[k];
      }
      for (int k = 0; k < 4; ++k) grad->rotation[i * 4 + k] = v_q[k];
    }
  });
}

void internal::preprocess_scalar(const GaussianSet<float>& g, const RasterCamera<float>& cam,
                                 const RasterSettings<float>& settings, RasterState<float>* s) {
  preprocess(g, cam, settings, s);
}

template void rasterize_forward<float>(const GaussianSet<float>&, const RasterCamera<float>&,
                                       const RasterSettings<float>&, RasterState<float>*);
template void rasterize_forward<double>(const GaussianSet<double>&, const RasterCamera<double>&,
                                        const RasterSettings<double>&, RasterState<double>*);
template void rasterize_backward<float>(const GaussianSet<float>&, const RasterCamera<float>&,
                                        const RasterSettings<float>&, RasterState<float>*,
                                        const std::vector<float>&, GaussianSet<float>*, std::vector<float>*);
template void rasterize_backward<double>(const GaussianSet<double>&, const RasterCamera<double>&,
                                         const RasterSettings<double>&, RasterState<double>*,
                                         const std::vector<double>&, GaussianSet<double>*, std::vector<double>*);

}  // namespace weathergs::reconstruction
