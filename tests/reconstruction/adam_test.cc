// The vectorized Adam update and finiteness scan (reconstruction/adam.h) against plain scalar loops
// of the same formulas: the same bits, whichever clone the CPU runs; and the update's fused check.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "core/rng.h"
#include "reconstruction/adam.h"

namespace weathergs::reconstruction {
namespace {

struct Arrays {
  std::vector<float> p, g, m, v;
};

Arrays random_arrays(int64_t n, uint64_t seed) {
  Arrays a;
  Rng rng(seed, 0, 0);
  for (int64_t i = 0; i < n; ++i) {
    a.p.push_back(float(rng.normal()));
    // Gradients over many magnitudes, zeros and denormals included.
    const double mag = std::pow(10.0, rng.uniform(-40, 3));
    a.g.push_back(i % 17 == 0 ? 0.f : float((rng.uniform_double() - 0.5) * mag));
    a.m.push_back(float(rng.normal() * 1e-3));
    a.v.push_back(float(rng.uniform_double() * 1e-4));
  }
  return a;
}

void scalar_update(Arrays* a, int64_t i, const AdamConstants& c, AdamRates r) {
  a->m[i] = c.beta1 * a->m[i] + (1.f - c.beta1) * a->g[i];
  a->v[i] = c.beta2 * a->v[i] + (1.f - c.beta2) * a->g[i] * a->g[i];
  a->p[i] -= r.step_size * a->m[i] / (std::sqrt(a->v[i]) / r.bc2_sqrt + c.eps);
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * 4) == 0;
}

TEST(AdamTest, UpdateEqualsTheScalarFormula) {
  const AdamConstants c;  // the trainer's betas and eps
  const AdamRates r{1.6e-4f / (1.f - 0.9f), std::sqrt(1.f - 0.999f)};
  for (int64_t n : {int64_t(1), int64_t(7), int64_t(1000), int64_t(4099)}) {  // tails of every length
    Arrays a = random_arrays(n, 11), b = a;
    EXPECT_TRUE(adam_update(a.p.data(), a.g.data(), a.m.data(), a.v.data(), n, c, r)) << n;
    for (int64_t i = 0; i < n; ++i) scalar_update(&b, i, c, r);
    EXPECT_TRUE(same_bits(a.p, b.p)) << n;
    EXPECT_TRUE(same_bits(a.m, b.m)) << n;
    EXPECT_TRUE(same_bits(a.v, b.v)) << n;
  }
}

TEST(AdamTest, RowsUseTheirColumnsRates) {
  const AdamConstants c;
  const AdamRates dc{2.5e-3f / 0.1f, 0.5f}, rest{1.25e-4f / 0.1f, 0.5f};
  const int width = 48, split = 3;
  const int64_t rows = 301;
  Arrays a = random_arrays(rows * width, 12), b = a;
  EXPECT_TRUE(adam_update_rows(a.p.data(), a.g.data(), a.m.data(), a.v.data(), rows, width, split, c, dc, rest));
  for (int64_t i = 0; i < rows * width; ++i) scalar_update(&b, i, c, i % width < split ? dc : rest);
  EXPECT_TRUE(same_bits(a.p, b.p));
  EXPECT_TRUE(same_bits(a.m, b.m));
  EXPECT_TRUE(same_bits(a.v, b.v));
}

// The fused finiteness check (the trainer's per-iteration guard): false for a non-finite gradient and
// for a parameter the update itself makes non-finite, in any position of the vector loop and its
// tail; every element is still updated as the scalar formula says.
TEST(AdamTest, UpdateReportsNonFiniteGradientsAndResults) {
  const AdamConstants c;
  const AdamRates r{1.6e-3f, std::sqrt(1.f - 0.999f)};
  const int64_t n = 1037;
  for (int64_t at : {int64_t(0), int64_t(5), int64_t(512), int64_t(1036)}) {
    for (float bad : {std::numeric_limits<float>::quiet_NaN(), -std::numeric_limits<float>::infinity()}) {
      Arrays a = random_arrays(n, 13), b = a;
      a.g[at] = b.g[at] = bad;
      EXPECT_FALSE(adam_update(a.p.data(), a.g.data(), a.m.data(), a.v.data(), n, c, r)) << at;
      for (int64_t i = 0; i < n; ++i) scalar_update(&b, i, c, r);
      EXPECT_TRUE(same_bits(a.p, b.p)) << at;
    }
    // A finite gradient that drives the parameter past FLT_MAX.
    Arrays a = random_arrays(n, 14);
    a.p[at] = std::numeric_limits<float>::max();
    a.m[at] = -1.f;
    a.g[at] = -1.f;
    const AdamRates huge{1e38f, 1.f};
    EXPECT_FALSE(adam_update(a.p.data(), a.g.data(), a.m.data(), a.v.data(), n, c, huge)) << at;
    EXPECT_TRUE(std::isinf(a.p[at])) << at;
    Arrays rows = random_arrays(n / 17 * 17, 15);
    rows.g[at % rows.g.size()] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_FALSE(adam_update_rows(rows.p.data(), rows.g.data(), rows.m.data(), rows.v.data(), n / 17, 17, 3, c, r, r));
  }
}

TEST(AdamTest, FirstNonFiniteFindsTheFirstBadElement) {
  std::vector<float> a(5000, 1.f);
  a[10] = std::numeric_limits<float>::max();
  a[11] = std::numeric_limits<float>::denorm_min();
  a[12] = -0.f;
  EXPECT_EQ(first_non_finite(a.data(), int64_t(a.size())), -1);
  EXPECT_EQ(first_non_finite(a.data(), 0), -1);
  for (float bad : {std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity(),
                    std::numeric_limits<float>::quiet_NaN(), -std::numeric_limits<float>::quiet_NaN()}) {
    std::vector<float> b = a;
    b[4321] = bad;
    b[4999] = bad;
    EXPECT_EQ(first_non_finite(b.data(), int64_t(b.size())), 4321);
    EXPECT_EQ(first_non_finite(b.data() + 4322, 678), 677);
  }
}

}  // namespace
}  // namespace weathergs::reconstruction
