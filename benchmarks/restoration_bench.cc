// Cost of the restoration part per view: the learned LED (shipped weights, models/led/led) at the
// paper's 600x400 and the quick 300x200, one view and a batch of 4; the classical AEF at 600x400; the
// learned AEF plugin (models/aef/derain) and the weather selector (models/aef/selector) per 600x400 view.
//   build/benchmarks/bench_restoration --benchmark_min_time=2        (threads: --threads N below)
#include <benchmark/benchmark.h>

#include <cmath>

#include "core/parallel.h"
#include "core/rng.h"
#include "restoration/aef/aef_plugin.h"
#include "restoration/led/lens_detector.h"
#include "restoration/aef/particle_filter.h"
#include "restoration/aef/weather_selector.h"

namespace {

using namespace weathergs;
using namespace weathergs::restoration;
using namespace weathergs::restoration::aef;
using namespace weathergs::restoration::led;

Image view(int w, int h) {
  Image a(w, h, 3);
  Rng rng(1, 0, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        a.at(x, y, c) = std::clamp(float(0.5 + 0.3 * std::sin(x * 0.05 + c) * std::cos(y * 0.03) + 0.05 * rng.normal()), 0.f, 1.f);
  return a;
}

const LensDetector& led() {
  static const LensDetector d = LensDetector::load(std::string(WEATHERGS_SOURCE_DIR) + "/models/led/led");
  return d;
}

void BM_LedView(benchmark::State& state) {
  set_num_threads(int(state.range(2)));
  const Image v = view(int(state.range(0)), int(state.range(1)));
  for (auto _ : state) benchmark::DoNotOptimize(led().attention(v, "bench"));
  set_num_threads(0);
}
void BM_LedBatch4(benchmark::State& state) {
  set_num_threads(int(state.range(2)));
  const std::vector<Image> v(4, view(int(state.range(0)), int(state.range(1))));
  for (auto _ : state) benchmark::DoNotOptimize(led().attention(v, "bench"));
  state.SetItemsProcessed(state.iterations() * 4);
  set_num_threads(0);
}
void BM_ClassicalAef(benchmark::State& state) {
  const Image v = view(600, 400);
  for (auto _ : state) benchmark::DoNotOptimize(filter_particles(v, {}, "bench"));
}

// One view on one libtorch thread (AefPlugin::restore); `weathergs filter` runs views in parallel.
void BM_LearnedAef(benchmark::State& state) {
  static const AefPlugin p = AefPlugin::load(std::string(WEATHERGS_SOURCE_DIR) + "/models/aef/derain", AefPluginKind::kDerain);
  const Image v = view(int(state.range(0)), int(state.range(1)));
  for (auto _ : state) benchmark::DoNotOptimize(p.restore(v, "bench"));
}
void BM_Selector(benchmark::State& state) {
  static const WeatherSelector s = WeatherSelector::load(std::string(WEATHERGS_SOURCE_DIR) + "/models/aef/selector");
  const Image v = view(600, 400);
  for (auto _ : state) benchmark::DoNotOptimize(s.select(s.embed(v, "bench")));
}

BENCHMARK(BM_LearnedAef)->Args({600, 400})->Args({300, 200})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Selector)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LedView)->Args({600, 400, 1})->Args({600, 400, 2})->Args({300, 200, 2})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_LedBatch4)->Args({600, 400, 2})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ClassicalAef)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
