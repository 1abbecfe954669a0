// One 3DGS training iteration (forward, loss, backward, Adam) on the CPU, and its phases.
// Scene: N Gaussians in a unit ball, log-uniform scales in [0.01, 0.1] m (1-10 px footprints at
// 300x200), seen from 4 m; the target image is a render of a perturbed copy, so gradients are dense.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "core/parallel.h"

#include "core/rng.h"
#include "reconstruction/loss.h"
#include "reconstruction/raster_internal.h"
#include "reconstruction/rasterizer.h"
#include "reconstruction/trainer.h"

namespace weathergs::reconstruction {
namespace {

Camera bench_camera(int width, int height) {
  Camera c;
  c.name = "bench";
  c.width = width;
  c.height = height;
  c.fx = c.fy = 0.9 * width;
  c.cx = width / 2.0;
  c.cy = height / 2.0;
  c.camera_from_world.setIdentity();
  c.camera_from_world(2, 3) = 4.0;  // looking down +z at the origin from 4 m
  return c;
}

GaussianSet<float> bench_gaussians(int n, uint64_t seed) {
  GaussianSet<float> g;
  g.assign_zero(n);
  for (int i = 0; i < n; ++i) {
    Rng rng(seed, 1, i);
    double x, y, z;
    do {
      x = rng.uniform(-1, 1); y = rng.uniform(-1, 1); z = rng.uniform(-1, 1);
    } while (x * x + y * y + z * z > 1);
    g.position[i * 3] = float(x * 1.5); g.position[i * 3 + 1] = float(y); g.position[i * 3 + 2] = float(z);
    for (int k = 0; k < 3; ++k) g.log_scale[i * 3 + k] = float(std::log(0.01) + rng.uniform_double() * std::log(10.0));
    for (int k = 0; k < 4; ++k) g.rotation[i * 4 + k] = float(rng.normal());
    g.opacity_logit[i] = float(rng.normal());
    for (int k = 0; k < kShFloats; ++k) g.sh[i * kShFloats + k] = float((k < 3 ? 1.0 : 0.1) * rng.normal());
  }
  return g;
}

TrainView bench_view(int width, int height, int n) {
  TrainView v;
  v.camera = bench_camera(width, height);
  GaussianSet<float> target = bench_gaussians(n, 2);
  RasterState<float> st;
  rasterize_forward(target, RasterCamera<float>::from(v.camera), RasterSettings<float>{}, &st);
  v.rgb = st.image;
  for (float& x : v.rgb) x = std::clamp(x, 0.f, 1.f);
  return v;
}

void BM_TrainIteration(benchmark::State& state) {
  const int width = int(state.range(0)), height = int(state.range(1)), n = int(state.range(2));
  TrainOptions o;
  o.iterations = 1 << 30;
  o.densify_until = 0;  // a plain iteration: no densification, fixed Gaussian count
  o.sh_degree_interval = 1;  // SH degree 3 from the first iteration on
  Trainer t({bench_view(width, height, n)}, bench_gaussians(n, 1), o, 4.0);
  for (int i = 0; i < 3; ++i) t.step();  // warm-up: buffers allocated
  for (auto _ : state) benchmark::DoNotOptimize(t.step());
  state.counters["gaussians"] = n;
}

struct Phases {
  RasterCamera<float> cam;
  RasterSettings<float> rs;
  GaussianSet<float> g, grad;
  TrainView view;
  RasterState<float> st;
  std::vector<float> v_image, v_ndc;
  Phases(int w, int h, int n) : g(bench_gaussians(n, 1)), view(bench_view(w, h, n)) {
    cam = RasterCamera<float>::from(view.camera);
    rasterize_forward(g, cam, rs, &st);
    photometric_loss<float>(st.image, view.rgb, nullptr, w, h, 0.2f, &v_image);
    rasterize_backward(g, cam, rs, &st, v_image, &grad, &v_ndc);
  }
};

// The training forward: everything the backward pass reads.
void BM_Forward(benchmark::State& state) {
  Phases p(int(state.range(0)), int(state.range(1)), int(state.range(2)));
  for (auto _ : state) rasterize_forward(p.g, p.cam, p.rs, &p.st);
  state.counters["entries"] = double(p.st.num_entries());
}

// A render (`weathergs render`, test views): the image only (RasterOutputs::kImage), through the
// fused image-only blend where the CPU has FMA (equal to the training forward up to rounding).
void BM_Render(benchmark::State& state) {
  Phases p(int(state.range(0)), int(state.range(1)), int(state.range(2)));
  p.rs.outputs = RasterOutputs::kImage;
  for (auto _ : state) rasterize_forward(p.g, p.cam, p.rs, &p.st);
  state.counters["entries"] = double(p.st.num_entries());
}

void BM_Loss(benchmark::State& state) {
  Phases p(int(state.range(0)), int(state.range(1)), 1000);
  for (auto _ : state)
    benchmark::DoNotOptimize(photometric_loss<float>(p.st.image, p.view.rgb, nullptr, p.view.camera.width,
                                                     p.view.camera.height, 0.2f, &p.v_image));
}

void BM_Backward(benchmark::State& state) {
  Phases p(int(state.range(0)), int(state.range(1)), int(state.range(2)));
  for (auto _ : state) rasterize_backward(p.g, p.cam, p.rs, &p.st, p.v_image, &p.grad, &p.v_ndc);
}

void sizes(benchmark::internal::Benchmark* b) {
  b->Args({300, 200, 50000})->Args({300, 200, 200000})->Args({600, 400, 50000})->Args({600, 400, 200000});
  b->Args({600, 400, 300000});  // a weathered paper-profile run before its budget (docs/record/convergence.md)
  b->Unit(benchmark::kMillisecond)->UseRealTime();
}

BENCHMARK(BM_TrainIteration)->Apply(sizes);
BENCHMARK(BM_Forward)->Apply(sizes);
BENCHMARK(BM_Render)->Apply(sizes);
BENCHMARK(BM_Backward)->Apply(sizes);
BENCHMARK(BM_Loss)->Args({300, 200, 0})->Args({600, 400, 0})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace weathergs::reconstruction

// WEATHERGS_THREADS caps the worker threads (0 or unset = all cores). With 1 thread the CPU column is
// the single-thread cost even on a loaded machine. WEATHERGS_TILE_WIDTH = 4 | 8 picks the tile
// kernels' lane count (default: the widest the CPU runs).
int main(int argc, char** argv) {
  const char* t = std::getenv("WEATHERGS_THREADS");
  weathergs::set_num_threads(t ? std::atoi(t) : 0);
  if (const char* w = std::getenv("WEATHERGS_TILE_WIDTH")) {
    if (!weathergs::reconstruction::internal::set_tile_kernel_width(std::atoi(w))) {
      std::fprintf(stderr, "WEATHERGS_TILE_WIDTH=%s: not 4 or 8, or not supported by this CPU\n", w);
      return 2;
    }
  }
  std::printf("tile kernel width: %d lanes\n", weathergs::reconstruction::internal::tile_kernel_width());
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
