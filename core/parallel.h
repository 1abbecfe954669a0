// The one ParallelFor of the project (oneTBB underneath).
//
// Contract: fn(i) is called exactly once for every i in [begin, end), from an unspecified thread, in
// an unspecified order. Results must therefore not depend on scheduling: write to per-index slots,
// or use parallel_for_chunks with per-chunk buffers reduced afterwards in chunk order. Chunk
// boundaries depend only on (begin, end, chunk_size), never on the thread count.
#pragma once

#include <cstdint>
#include <functional>

namespace weathergs {

// Caps the worker threads for the whole process (0 = all cores). Returns the number in effect.
int set_num_threads(int n);
int num_threads();

void parallel_for(int64_t begin, int64_t end, const std::function<void(int64_t)>& fn,
                  int64_t grain = 1);

// Splits [begin, end) into fixed chunks [begin + k*chunk_size, ...) and calls fn(chunk_index, lo, hi).
int64_t num_chunks(int64_t begin, int64_t end, int64_t chunk_size);
void parallel_for_chunks(int64_t begin, int64_t end, int64_t chunk_size,
                         const std::function<void(int64_t chunk, int64_t lo, int64_t hi)>& fn);

}  // namespace weathergs
