// The image-only render's 8-lane tile kernel with fused multiply-add: the forward blend of
// raster_blend_simd.h (render_tile<8, false>), compiled in this translation unit with
// -ffp-contract=fast (reconstruction/CMakeLists.txt) and the FMA target, so that its products and
// sums fuse (the exp polynomial, the block power in Horner form, the colour and transmittance
// updates). It serves renders only (RasterOutputs::kImage: `weathergs render`, depth maps, the
// evaluation of test views); the training forward, whose arithmetic the backward pass replays, stays
// unfused in raster_simd.cc. Measured ~15 % less blend time on the bench scene (benchmarks/README.md);
// the images match the training forward's up to rounding (test
// RasterizerTest.ImageOnlyForwardMatchesTheTrainingForward). The dispatch is render_tile_simd.
#include "reconstruction/raster_blend_simd.h"
#include "reconstruction/raster_internal.h"

namespace weathergs::reconstruction::internal {

#if defined(__x86_64__) && defined(__GNUC__)
__attribute__((target("avx2,fma"))) void render_image_tile_fused(const RasterSettings<float>& settings,
                                                                 RasterState<float>* s, int64_t tile) {
  render_tile<8, false>(settings, s, tile);
}
#else
// Not dispatched (fused_image_kernel() is false where the 8-lane kernels are not built); still a
// correct image-only kernel, contracted wherever the target has a fused multiply-add.
void render_image_tile_fused(const RasterSettings<float>& settings, RasterState<float>* s, int64_t tile) {
  render_tile<8, false>(settings, s, tile);
}
#endif

}  // namespace weathergs::reconstruction::internal
