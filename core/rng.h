// Counter-based random numbers (Philox4x32-10, Salmon et al. 2011, "Parallel random numbers: as easy
// as 1, 2, 3"). The stream is keyed on (seed, stream, index): the numbers a work item draws depend
// only on its identity, never on threads or on the order items are processed in.
//
//   Rng rng(seed, kStreamParticleInit, particle_id);
//   float u = rng.uniform();      // [0, 1)
#pragma once

#include <array>
#include <cstdint>

namespace weathergs {

std::array<uint32_t, 4> philox4x32_10(std::array<uint32_t, 4> counter, std::array<uint32_t, 2> key);

class Rng {
 public:
  Rng(uint64_t seed, uint64_t stream, uint64_t index);

  uint32_t next_u32();
  uint64_t next_u64();
  float uniform();               // [0, 1), 24 bits
  double uniform_double();       // [0, 1), 53 bits
  float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
  double normal();               // standard normal (Box-Muller on uniform_double)
  uint32_t uniform_int(uint32_t n);  // [0, n), unbiased (rejection)

 private:
  void refill();
  std::array<uint32_t, 2> key_;
  std::array<uint32_t, 4> counter_;
  std::array<uint32_t, 4> block_{};
  int used_ = 4;
};

}  // namespace weathergs
