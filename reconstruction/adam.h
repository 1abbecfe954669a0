// The trainer's element-wise kernels over the parameter arrays: the Adam update (with a fused
// finiteness check of its inputs and outputs) and the finiteness scan. Both are branch-free loops
// that the compiler vectorizes, with an AVX2 clone (cpu_clones.h); sqrt and division are correctly
// rounded, so every clone gives the same bits.
#pragma once

#include <cstdint>

namespace weathergs::reconstruction {

// One parameter group's Adam rates at this step: p -= step_size m / (sqrt(v) / bc2_sqrt + eps),
// with step_size = lr / (1 - beta1^t) and bc2_sqrt = sqrt(1 - beta2^t) (the reference's torch.optim.Adam).
struct AdamRates {
  float step_size = 0;
  float bc2_sqrt = 1;
};

struct AdamConstants {
  float beta1 = 0.9f, beta2 = 0.999f, eps = 1e-15f;
};

// Updates n elements of one group (moments m, v in place). Returns false when some gradient or
// updated parameter is not finite (all elements are updated regardless).
bool adam_update(float* p, const float* grad, float* m, float* v, int64_t n, const AdamConstants& c, AdamRates rates);

// Updates `rows` rows of `width` floats whose columns [0, split) use `first` and [split, width) use
// `rest` (the SH rows: 3 DC coefficients, then 45 at a twentieth of the rate). width <= 64.
// Returns false as adam_update does.
bool adam_update_rows(float* p, const float* grad, float* m, float* v, int64_t rows, int width, int split,
                      const AdamConstants& c, AdamRates first, AdamRates rest);

// Index of the first non-finite element of a[0, n), or -1.
int64_t first_non_finite(const float* a, int64_t n);

}  // namespace weathergs::reconstruction
