// Cost of scoring one 600x400 RGB pair: PSNR, SSIM and LPIPS separately, and the whole protocol.
//   build/benchmarks/bench_evaluator --benchmark_min_time=2
#include <benchmark/benchmark.h>

#include <cmath>

#include "core/parallel.h"
#include "core/rng.h"
#include "evaluator/evaluate.h"

namespace {

using namespace weathergs;
using namespace weathergs::evaluator;

std::pair<Image, Image> pair_600x400() {
  Image a(600, 400, 3), b(600, 400, 3);
  Rng rng(1, 0, 0);
  for (int y = 0; y < 400; ++y)
    for (int x = 0; x < 600; ++x)
      for (int c = 0; c < 3; ++c) {
        float v = float(0.5 + 0.3 * std::sin(x * 0.05 + c) * std::cos(y * 0.03));
        a.at(x, y, c) = std::round(v * 255) / 255;
        b.at(x, y, c) = std::round(std::clamp(v + 0.03f * float(rng.normal()), 0.f, 1.f) * 255) / 255;
      }
  return {a, b};
}

void BM_Psnr(benchmark::State& state) {
  auto [a, b] = pair_600x400();
  for (auto _ : state) benchmark::DoNotOptimize(psnr(a, b));
}
void BM_Ssim(benchmark::State& state) {
  auto [a, b] = pair_600x400();
  for (auto _ : state) benchmark::DoNotOptimize(ssim(a, b));
}
void BM_Lpips(benchmark::State& state) {
  auto [a, b] = pair_600x400();
  Lpips lpips(find_lpips_model({std::string(WEATHERGS_SOURCE_DIR) + "/models/lpips"}));
  for (auto _ : state) benchmark::DoNotOptimize(lpips.distance(a, b));
}
void BM_ScorePairProtocol(benchmark::State& state) {
  auto [a, b] = pair_600x400();
  Lpips lpips(find_lpips_model({std::string(WEATHERGS_SOURCE_DIR) + "/models/lpips"}));
  ScoringOptions o;
  for (auto _ : state) benchmark::DoNotOptimize(score_pair(a, b, o, &lpips, nullptr, "bench"));
}

BENCHMARK(BM_Psnr)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Ssim)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Lpips)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ScorePairProtocol)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
