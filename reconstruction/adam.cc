#include "reconstruction/adam.h"

#include <cmath>
#include <cstring>

#include "core/error.h"
#include "reconstruction/cpu_clones.h"

namespace weathergs::reconstruction {

namespace {

// Whether a float is Inf or NaN (exponent bits all set), by integer operations only, so that loops
// using it vectorize and never trap.
inline uint32_t non_finite_bit(float x) {
  uint32_t bits;
  std::memcpy(&bits, &x, 4);
  return uint32_t((bits & 0x7f800000u) == 0x7f800000u);
}

// The update of one element, in the order of the reference's arithmetic. Returns 1 when the
// gradient or the updated parameter is not finite (the trainer's finiteness check, fused here so
// that the arrays are not read a second time).
inline uint32_t update(float& p, float g, float& m, float& v, const AdamConstants& c, float step_size, float bc2_sqrt) {
  m = c.beta1 * m + (1.f - c.beta1) * g;
  v = c.beta2 * v + (1.f - c.beta2) * g * g;
  p -= step_size * m / (std::sqrt(v) / bc2_sqrt + c.eps);
  return non_finite_bit(g) | non_finite_bit(p);
}

WGS_AVX2_CLONES uint32_t update_span(float* __restrict p, const float* __restrict grad, float* __restrict m,
                                     float* __restrict v, int64_t n, AdamConstants c, float step_size, float bc2_sqrt) {
  uint32_t bad = 0;
  for (int64_t i = 0; i < n; ++i) bad |= update(p[i], grad[i], m[i], v[i], c, step_size, bc2_sqrt);
  return bad;
}

WGS_AVX2_CLONES uint32_t update_rows(float* __restrict p, const float* __restrict grad, float* __restrict m,
                                     float* __restrict v, int64_t rows, int width, AdamConstants c,
                                     const float* __restrict step_size, const float* __restrict bc2_sqrt) {
  uint32_t bad = 0;
  for (int64_t r = 0; r < rows; ++r) {
    const int64_t o = r * width;
    for (int j = 0; j < width; ++j)
      bad |= update(p[o + j], grad[o + j], m[o + j], v[o + j], c, step_size[j], bc2_sqrt[j]);
  }
  return bad;
}

// Non-zero when some element is Inf or NaN.
WGS_AVX2_CLONES uint32_t any_non_finite(const float* __restrict a, int64_t n) {
  uint32_t bad = 0;
  for (int64_t i = 0; i < n; ++i) bad |= non_finite_bit(a[i]);
  return bad;
}

}  // namespace

bool adam_update(float* p, const float* grad, float* m, float* v, int64_t n, const AdamConstants& c, AdamRates rates) {
  return update_span(p, grad, m, v, n, c, rates.step_size, rates.bc2_sqrt) == 0;
}

bool adam_update_rows(float* p, const float* grad, float* m, float* v, int64_t rows, int width, int split,
                      const AdamConstants& c, AdamRates first, AdamRates rest) {
  constexpr int kMaxWidth = 64;
  WGS_CHECK(width > 0 && width <= kMaxWidth && split >= 0 && split <= width);
  float step_size[kMaxWidth], bc2_sqrt[kMaxWidth];
  for (int j = 0; j < width; ++j) {
    step_size[j] = j < split ? first.step_size : rest.step_size;
    bc2_sqrt[j] = j < split ? first.bc2_sqrt : rest.bc2_sqrt;
  }
  return update_rows(p, grad, m, v, rows, width, c, step_size, bc2_sqrt) == 0;
}

int64_t first_non_finite(const float* a, int64_t n) {
  if (!any_non_finite(a, n)) return -1;
  for (int64_t i = 0; i < n; ++i)
    if (!std::isfinite(a[i])) return i;
  return -1;
}

}  // namespace weathergs::reconstruction
