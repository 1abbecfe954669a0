// Accuracy costs time: one 600x400 view with rain at 25 mm/h (synthetic wall scene, f = 520 px,
// 1/60 s, f/2.8 35 mm focused at 10 m), rendered by the rain stage under each quality setting.
// Prints Google Benchmark timings, then a table of milliseconds against the error of the weathered
// image (sRGB, [0, 1]) relative to the highest-quality setting: PSNR and max abs error in 8-bit
// levels, plus the max abs error of the particle alpha layer.
//
//   build-gen/benchmarks/bench_generator_weather --benchmark_min_time=0.5
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "core/dataset.h"
#include "core/image.h"
#include "core/parallel.h"
#include "generator/stages.h"
#include "generator/weather.h"
#include "tests/generator/test_scene.h"

namespace weathergs::generator {
namespace {

struct Setting {
  std::string name;
  RenderOptions options;
};

struct Scene {
  Camera camera;
  Image clean, depth;
  EnvironmentLight env;
};

const Scene& scene() {
  static const Scene s = [] {
    const std::string dir = (std::filesystem::temp_directory_path() / "weathergs_bench_generator").string();
    std::filesystem::remove_all(dir);
    testing::SceneOptions o;
    o.views = 1, o.width = 600, o.height = 400, o.fx = 520, o.thin_lens = true;
    testing::make_clean_dataset(dir, o);
    const Dataset d = read_dataset(dir);
    Scene sc;
    sc.camera = d.cameras[0];
    sc.clean = to_linear(read_image(d.path(ImageKind::kClean, sc.camera.name)));
    sc.depth = read_depth(d.path(ImageKind::kDepth, sc.camera.name));
    const auto sky = estimate_sky_radiance(sc.clean);
    sc.env = make_environment_light(sc.clean, Eigen::Vector3f(float(sky[0]), float(sky[1]), float(sky[2])));
    std::filesystem::remove_all(dir);
    return sc;
  }();
  return s;
}

ParticleEffectSpec rain() {
  ParticleEffectSpec e;
  e.species.rate_mm_h = 25;
  e.species.wind.mean_m_s = {1.0, 0.5, 0.0};
  e.species.wind.turbulence_rms_m_s = 0.25 * e.species.wind.mean_m_s.norm();
  return e;
}

struct Result {
  Image srgb, alpha;
  int64_t drawn = 0;
};

Result render(const RenderOptions& options) {
  const Scene& s = scene();
  const ParticleStage stage(rain(), options, 7, false);
  WeatherView v(s.camera, s.clean, s.depth, s.env);
  stage.run(v);
  return {to_srgb(v.radiance), v.particle_alpha, v.counters["rain.particles_drawn"]};
}

std::vector<Setting> settings() {
  std::vector<Setting> list;
  auto add = [&](const std::string& name, auto edit) {
    RenderOptions o;
    edit(o);
    list.push_back({name, o});
  };
  add("default (analytic, cutoff 0.01, defocus)", [](RenderOptions&) {});
  add("analytic, 4 segments", [](RenderOptions& o) { o.segments = 4; });
  for (int n : {1, 2, 4, 8, 16, 32, 64})
    add("time samples " + std::to_string(n), [n](RenderOptions& o) {
      o.streak = StreakMode::kTimeSamples;
      o.time_samples = n;
    });
  for (double c : {0.05, 0.02, 0.005, 0.002})
    add("cutoff " + std::to_string(c).substr(0, 5), [c](RenderOptions& o) { o.visibility_cutoff = c; });
  add("defocus off", [](RenderOptions& o) { o.defocus = false; });
  return list;
}

// Highest quality: analytic with 16 segments per exposure, cutoff 0.001, defocus on.
RenderOptions reference_options() {
  RenderOptions o;
  o.segments = 16;
  o.visibility_cutoff = 0.001;
  return o;
}

void BM_Rain(benchmark::State& state, RenderOptions options) {
  scene();
  int64_t drawn = 0;
  for (auto _ : state) {
    Result r = render(options);
    drawn = r.drawn;
    benchmark::DoNotOptimize(r.srgb.data.data());
  }
  state.counters["particles_drawn"] = double(drawn);
}

// The physical shading's per-view cost: the environment and the water-sphere radiance grid.
void BM_WaterRadianceGrid(benchmark::State& state) {
  const Scene& sc = scene();
  for (auto _ : state) {
    const ViewEnvironment env(sc.camera, sc.clean, sc.env.sky);
    const ParticleRadianceGrid grid(env, sc.camera, ParticleOptics::kWaterSphere, 0);
    benchmark::DoNotOptimize(grid.at(300, 200));
  }
}

}  // namespace
}  // namespace weathergs::generator

int main(int argc, char** argv) {
  using namespace weathergs;
  using namespace weathergs::generator;
  const std::vector<Setting> list = settings();
  for (const Setting& s : list) benchmark::RegisterBenchmark(("rain_600x400/" + s.name).c_str(), BM_Rain, s.options)
                                    ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("water_radiance_grid_600x400", BM_WaterRadianceGrid)->Unit(benchmark::kMillisecond);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();

  // Error table (each setting timed once more here, wall clock, same threads).
  const auto t0 = std::chrono::steady_clock::now();
  const Result ref = render(reference_options());
  const double ref_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf("\nthreads %d; reference: analytic 16 segments, cutoff 0.001, defocus: %.0f ms, %lld particles drawn\n",
              num_threads(), ref_ms, (long long)ref.drawn);
  // A second reference isolates the streak knobs: the same cutoff and defocus as each setting,
  // analytic with 16 segments.
  std::printf("| setting | ms | particles drawn | PSNR vs reference (dB) | max abs error (8-bit levels) | max abs alpha error "
              "| PSNR vs 16-segment analytic at the same cutoff/defocus (dB) | max abs error there (8-bit) |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const Setting& s : list) {
    const auto a = std::chrono::steady_clock::now();
    const Result r = render(s.options);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - a).count();
    double se = 0, max_abs = 0, max_alpha = 0;
    for (size_t i = 0; i < r.srgb.data.size(); ++i) {
      const double d = double(r.srgb.data[i]) - ref.srgb.data[i];
      se += d * d;
      max_abs = std::max(max_abs, std::abs(d));
    }
    for (size_t i = 0; i < r.alpha.data.size(); ++i)
      max_alpha = std::max(max_alpha, double(std::abs(r.alpha.data[i] - ref.alpha.data[i])));
    const double mse = se / double(r.srgb.data.size());
    const double psnr = mse > 0 ? 10 * std::log10(1.0 / mse) : INFINITY;
    RenderOptions same = s.options;
    same.streak = StreakMode::kAnalytic;
    same.segments = 16;
    const Result r16 = render(same);
    double se16 = 0, max16 = 0;
    for (size_t i = 0; i < r.srgb.data.size(); ++i) {
      const double d = double(r.srgb.data[i]) - r16.srgb.data[i];
      se16 += d * d;
      max16 = std::max(max16, std::abs(d));
    }
    const double mse16 = se16 / double(r.srgb.data.size());
    const double psnr16 = mse16 > 0 ? 10 * std::log10(1.0 / mse16) : INFINITY;
    std::printf("| %s | %.0f | %lld | %.1f | %.1f | %.3f | %.1f | %.1f |\n", s.name.c_str(), ms, (long long)r.drawn, psnr,
                max_abs * 255, max_alpha, psnr16, max16 * 255);
  }
  return 0;
}
