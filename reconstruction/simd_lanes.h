// The vector types of the float SIMD translation units (raster_simd.cc, preprocess_simd.cc): W
// float or int32 lanes as GCC/Clang vector extensions. Include only from those .cc files.
#pragma once

#include <cstdint>

// Every helper is inlined into its caller, so no vector crosses a call boundary: the ABI note GCC
// gives for the 32- and 64-byte vectors of the default-target helpers does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"
#define WGS_ALWAYS_INLINE inline __attribute__((always_inline))

namespace weathergs::reconstruction::internal {

template <int W>
struct Lanes {
  typedef float f __attribute__((vector_size(4 * W)));
  typedef int32_t i __attribute__((vector_size(4 * W)));
};

}  // namespace weathergs::reconstruction::internal
