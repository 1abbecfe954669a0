#include "core/parallel.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <memory>

#include "core/error.h"

namespace weathergs {

namespace {
std::unique_ptr<tbb::global_control>& control() {
  static std::unique_ptr<tbb::global_control> c;
  return c;
}
int g_threads = 0;
}  // namespace

int set_num_threads(int n) {
  WGS_CHECK_GE(n, 0);
  int hw = tbb::info::default_concurrency();
  g_threads = n == 0 ? hw : n;
  control() = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                    size_t(g_threads));
  return g_threads;
}

int num_threads() {
  return g_threads > 0 ? g_threads : int(tbb::global_control::active_value(
                                         tbb::global_control::max_allowed_parallelism));
}

void parallel_for(int64_t begin, int64_t end, const std::function<void(int64_t)>& fn, int64_t grain) {
  if (end <= begin) return;
  if (num_threads() == 1 || end - begin == 1) {
    for (int64_t i = begin; i < end; ++i) fn(i);
    return;
  }
  tbb::parallel_for(tbb::blocked_range<int64_t>(begin, end, std::max<int64_t>(1, grain)),
                    [&](const tbb::blocked_range<int64_t>& r) {
                      for (int64_t i = r.begin(); i != r.end(); ++i) fn(i);
                    });
}

int64_t num_chunks(int64_t begin, int64_t end, int64_t chunk_size) {
  WGS_CHECK_GT(chunk_size, 0);
  return end <= begin ? 0 : (end - begin + chunk_size - 1) / chunk_size;
}

void parallel_for_chunks(int64_t begin, int64_t end, int64_t chunk_size,
                         const std::function<void(int64_t, int64_t, int64_t)>& fn) {
  const int64_t n = num_chunks(begin, end, chunk_size);
  parallel_for(0, n, [&](int64_t k) {
    int64_t lo = begin + k * chunk_size;
    fn(k, lo, std::min(end, lo + chunk_size));
  });
}

}  // namespace weathergs
