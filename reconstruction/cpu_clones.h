// WGS_AVX2_CLONES: GCC target_clones for the reconstruction's element-wise loops, an AVX2 clone
// beside the portable default, chosen by the loader from the CPU. The library compiles with
// -ffp-contract=off (CMakeLists.txt), so the clones only widen element-wise IEEE operations and give
// the same bits as the default (tests reconstruction/adam and reconstruction/rasterizer).
#pragma once

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define WGS_AVX2_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define WGS_AVX2_CLONES
#endif
