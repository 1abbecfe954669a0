// Tile-based Gaussian rasterizer on the CPU: the forward and backward passes of the reference
// diff-gaussian-rasterization, with the same constants (gaussian_math.h).
//
// Forward: per Gaussian (parallel) projection, 2D covariance and SH colour; its pixel box: the
// pixels of the reference's 16x16 tiles of its 3-sigma radius within the box where its alpha can
// reach 1/255 (the blend's own cut-off, so images are unchanged); binning of the box into 32x32
// tiles, less those (tested exactly) outside that ellipse; per-tile lists sorted by depth (ties by
// index); per tile (parallel) front-to-back blending within each box. Backward: per tile (parallel) back-to-front replay of each
// pixel's blend, one gradient slot per (tile, Gaussian) entry; then per Gaussian (parallel) the slots
// are summed in tile order and pulled back to the parameters. No float atomics, no per-thread
// buffers: results are bitwise independent of the thread count.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/aligned_allocator.h"
#include "reconstruction/gaussian_math.h"
#include "reconstruction/gaussians.h"

namespace weathergs::reconstruction {

// What a forward pass leaves in the RasterState.
enum class RasterOutputs {
  kTraining,  // everything rasterize_backward reads
  kImage,     // the image, for renders that are not trained on (test views, depth maps): the float
              // pass skips the 2D values, entry slots, final transmittance and contributor counts
              // that only the backward pass reads, and blends with fused multiply-add where the CPU
              // has it (the training forward's image up to rounding, docs/reconstruction.md);
              // rasterize_backward refuses it
};

template <typename T>
struct RasterSettings {
  int sh_degree = kMaxShDegree;  // active SH degree, 0..3
  std::array<T, 3> background = {T(0), T(0), T(0)};
  RasterOutputs outputs = RasterOutputs::kTraining;
};

// Everything the forward pass produces and the backward pass consumes. Reused between iterations
// (vectors keep their capacity).
constexpr int kSplatFloats = 16;
constexpr int kMaskTiles = 64;

template <typename T>
struct RasterState {
  int width = 0, height = 0, tiles_x = 0, tiles_y = 0;
  RasterOutputs outputs = RasterOutputs::kTraining;  // what the last forward pass wrote
  // Per Gaussian.
  std::vector<T> mean2d;         // N x 2, pixels
  std::vector<T> cov2d;          // N x 3 (a, b, c) of [[a, b], [b, c]], px^2, low-pass included
  std::vector<T> conic;          // N x 3, inverse of cov2d
  std::vector<T> opacity;        // N, sigmoid(logit)
  std::vector<T> color;          // N x 3
  std::vector<T> scale;          // N x 3, exp(log_scale) as the forward pass computed it
  std::vector<T> depth;          // N, camera z
  std::vector<int32_t> radius;   // N, reference radius in px; 0 = not rendered
  std::vector<int32_t> rect;     // N x 4: tile x0, y0, x1, y1 (exclusive): the tiles of the
                                 // record's pixel box (below); may be empty
  std::vector<uint64_t> tile_mask;  // N: bit b set when tile b (row-major) of a rect of at most
                                    // kMaskTiles tiles meets the alpha >= 1/255 ellipse; larger
                                    // rects have an entry in every tile
  std::vector<uint8_t> clamped;  // N, bit c set when colour channel c was clamped at 0
  // Packed per-Gaussian record read by the tile loops (one cache line): mean x, y, conic a, b, c,
  // opacity, r, g, b, the half extents (px) of the region where alpha can reach 1/255, the
  // largest d^T conic d there (2 ln(255 o) with a rounding margin; -1 when alpha never reaches it),
  // and the pixel box the kernels blend in (first and last column, first and last row, as floats):
  // the alpha extents' box within the reference's 3-sigma rectangle of 16x16 tiles. 64-byte
  // aligned, so that a float record (16 floats) is one cache line and the kernels' one prefetch per
  // record fetches all of it.
  std::vector<T, AlignedAllocator<T, 64>> splat;  // N x kSplatFloats
  std::vector<int64_t> entry_offset;  // N + 1: first slot of each Gaussian in the per-Gaussian order
  // Per tile.
  std::vector<int64_t> tile_offset;   // tiles + 1
  std::vector<int32_t> tile_gaussian;  // entries: the Gaussian's index, each tile's range sorted by
                                       // (depth, index)
  std::vector<int32_t> entry_slot;    // entries: the entry's slot in the per-Gaussian order (each
                                      // Gaussian's entries contiguous, its tiles in row-major order)
  // Per pixel.
  std::vector<T> image;          // H x W x 3
  std::vector<T> final_transmittance;  // H x W
  std::vector<int32_t> n_contrib;      // H x W: entries [0, n) of the tile list were visited
  // Scratch of the backward pass: 9 gradients per entry (mean x/y, conic a/b/c, opacity, rgb), at
  // the entry's slot in the per-Gaussian order, so that the per-Gaussian sums read them in sequence.
  std::vector<T> entry_grad;

  int64_t num_entries() const { return tile_offset.empty() ? 0 : tile_offset.back(); }
};

// Renders `g` into state->image. The model's SH array must hold degree 3 (48 floats per Gaussian);
// only the first (sh_degree + 1)^2 coefficients are used.
template <typename T>
void rasterize_forward(const GaussianSet<T>& g, const RasterCamera<T>& camera, const RasterSettings<T>& settings,
                       RasterState<T>* state);

// Gradients of a scalar loss given dL/dimage (H x W x 3). Overwrites *grad (resized to g's size).
// If v_mean2d_ndc is given, it receives dL/d(mean in NDC) per Gaussian (N x 2), the view-space
// positional gradient that the reference's densification measures (pixels = (ndc + 1) * W / 2).
template <typename T>
void rasterize_backward(const GaussianSet<T>& g, const RasterCamera<T>& camera, const RasterSettings<T>& settings,
                        RasterState<T>* state, const std::vector<T>& v_image, GaussianSet<T>* grad,
                        std::vector<T>* v_mean2d_ndc = nullptr);

// The largest blend weight alpha * T (the share of a pixel's colour it gives) that each Gaussian
// has at any pixel of the image the last forward pass rendered, in `weights` (N; 0 where it blends
// nowhere). A separate replay of the training forward's per-pixel blend, so that a forward pass
// costs nothing more when nobody asks; it reads only the tile lists and records, which both
// RasterOutputs write alike. A maximum does not depend on the order the tiles run in: the same bits
// with any thread count. What Mini-Splatting's simplification ranks Gaussians by (the trainer's
// blend-weight prune, trainer.h).
template <typename T>
void max_blend_weights(const RasterState<T>& state, std::vector<T>* weights);

}  // namespace weathergs::reconstruction
