// The 3DGS trainer's numerics version: which trained bits a given recipe, dataset and seed give. A
// run's recipe records it (docs/archive.md), so that results made by trainers that round differently
// are never mistaken for one recipe. Any change that alters the trained bits (an operation's order,
// a kernel, a default inside the trainer, the initialization) must bump it; test
// reconstruction/numerics_golden fails when the bits move while it stays, and says how to regenerate
// the golden hash (tests/data/numerics_golden.json).
#pragma once

namespace weathergs::reconstruction {

inline constexpr const char* kTrainerNumericsVersion = "3dgs-numerics-1";

}  // namespace weathergs::reconstruction
