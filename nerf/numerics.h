// The radiance-field trainer's numerics version: which trained bits a given recipe, dataset and seed
// give. A run's recipe records it (docs/archive.md). Any change that alters the trained field (the
// march, the grid, the sampling of rays, the optimizer) must bump it; test nerf/numerics_golden fails
// when the bits move while it stays, and says how to regenerate the golden hash
// (tests/data/numerics_golden.json).
#pragma once

namespace weathergs::nerf {

inline constexpr const char* kFieldNumericsVersion = "nerf-numerics-1";

}  // namespace weathergs::nerf
