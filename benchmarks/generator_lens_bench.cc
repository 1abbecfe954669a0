// Lens droplets: time and error per view against samples per pixel and cap geometry.
//
//   bench_generator_lens [--dump=DIR | --time_default=VIEWS] [google benchmark flags]
//
// One 600x400 view (fx 520), the spec's default drops (60, radius 0.5-3 mm log-uniform, contact
// angle 70 deg, glass at 3 cm). Error: RMSE (linear radiance) and PSNR against a 64-spp analytic
// reference rendered with independent pixel noise (another view name, same drops), over the whole
// view and over the pixels the reference shows water in. "defocus" uses docs/formats.md's camera
// (f/2.8, 35 mm, focus 10 m); without it the camera is a pinhole.
#include <benchmark/benchmark.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>

#include "core/image.h"
#include "generator/lens/lens_render.h"

namespace weathergs::generator::lens {
namespace {

Camera bench_camera(bool defocus, const std::string& name) {
  Camera c;
  c.name = name;
  c.width = 600;
  c.height = 400;
  c.fx = c.fy = 520;
  c.cx = 300;
  c.cy = 200;
  if (defocus) {
    c.f_number = 2.8;
    c.focal_length_mm = 35;
    c.focus_distance_m = 10;
  }
  return c;
}

// A street-like linear image: bright sky gradient above, darker ground, colored posts.
Image bench_image() {
  Image img(600, 400, 3, ColorSpace::kLinear);
  for (int y = 0; y < 400; ++y)
    for (int x = 0; x < 600; ++x) {
      const double v = (y + 0.5) / 400;
      double r, g, b;
      if (v < 0.55) {
        r = 0.35 + 0.3 * v, g = 0.5 + 0.3 * v, b = 0.9 - 0.2 * v;
      } else {
        const bool tile = ((x / 25) + (y / 25)) % 2;
        r = g = b = tile ? 0.12 : 0.2;
      }
      if (x % 120 < 10 && v > 0.2) r = 0.8, g = 0.15, b = 0.1;
      img.at(x, y, 0) = float(r);
      img.at(x, y, 1) = float(g);
      img.at(x, y, 2) = float(b);
    }
  return img;
}

LensDropletSpec bench_spec(int spp, bool triangles) {
  LensDropletSpec s;  // the documented defaults
  s.samples_per_pixel = spp;
  s.geometry = triangles ? CapGeometry::kTriangles : CapGeometry::kAnalytic;
  return s;
}

constexpr uint64_t kSeed = 7;

const LensViewResult& reference(bool defocus) {
  static std::map<bool, LensViewResult> cache;
  auto it = cache.find(defocus);
  if (it == cache.end()) {
    const Camera cam = bench_camera(defocus, "reference");
    LensDropletRenderer r(bench_spec(64, false), kSeed, cam);
    it = cache.emplace(defocus, r.render(bench_image(), cam, 0.0)).first;
  }
  return it->second;
}

void BM_LensView(benchmark::State& state) {
  const int spp = int(state.range(0));
  const bool triangles = state.range(1) != 0, defocus = state.range(2) != 0;
  const Camera cam = bench_camera(defocus, "000");
  const Image img = bench_image();
  const LensViewResult& ref = reference(defocus);
  LensDropletRenderer renderer(bench_spec(spp, triangles), kSeed, cam);
  LensViewResult out;
  double trace_s = 0, blur_s = 0;
  int64_t embree_rays = 0, camera_rays = 0;
  for (auto _ : state) {
    out = renderer.render(img, cam, 0.0);
    trace_s += out.trace_seconds;
    blur_s += out.blur_seconds;
    embree_rays += out.embree_rays;
    camera_rays += out.camera_rays;
  }
  double se = 0, se_water = 0;
  int64_t n_water = 0;
  for (size_t i = 0; i < out.image.data.size(); ++i) {
    const double e = double(out.image.data[i]) - ref.image.data[i];
    se += e * e;
    if (ref.coverage.data[i / 3] > 0) {
      se_water += e * e;
      ++n_water;
    }
  }
  const double rmse = std::sqrt(se / out.image.data.size());
  const double rmse_water = n_water ? std::sqrt(se_water / n_water) : 0;
  state.counters["rmse"] = rmse;
  state.counters["psnr_db"] = rmse > 0 ? 20 * std::log10(1.0 / rmse) : 999;
  state.counters["rmse_water"] = rmse_water;
  state.counters["trace_ms"] = 1e3 * trace_s / state.iterations();
  state.counters["blur_ms"] = 1e3 * blur_s / state.iterations();
  state.counters["Mrays_s"] = embree_rays / std::max(trace_s, 1e-12) / 1e6;
  state.counters["cam_Mrays_s"] = camera_rays / std::max(trace_s, 1e-12) / 1e6;
  state.counters["coverage"] = [&] {
    double s = 0;
    for (float v : out.coverage.data) s += v;
    return s / out.coverage.data.size();
  }();
  state.SetLabel(std::string(triangles ? "triangles" : "analytic") + (defocus ? " defocus" : " pinhole"));
}

BENCHMARK(BM_LensView)
    ->ArgsProduct({{1, 4, 16, 64}, {0, 1}, {0, 1}})
    ->ArgNames({"spp", "tri", "defocus"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(0.3);

// Writes the default-setting render for a visual check: input, output, coverage, mask (sRGB PNG).
void dump(const std::string& dir) {
  std::filesystem::create_directories(dir);
  const Image img = bench_image();
  for (int variant = 0; variant < 3; ++variant) {
    Camera cam = bench_camera(variant == 1, "000");
    if (variant == 2) {  // a phone-like lens with the same field of view: f = 4 mm, f/2, focus 3 m
      cam.f_number = 2.0;
      cam.focal_length_mm = 4;
      cam.focus_distance_m = 3;
    }
    LensViewResult out = LensDropletRenderer(bench_spec(16, false), kSeed, cam).render(img, cam, 0.0);
    const std::string tag = variant == 0 ? "pinhole" : variant == 1 ? "defocus" : "phone";
    write_image(dir + "/input.png", img);
    write_image(dir + "/output_" + tag + ".png", out.image);
    Image cov = out.coverage;
    cov.space = ColorSpace::kSRGB;
    write_image(dir + "/coverage_" + tag + ".png", cov);
    write_mask(dir + "/mask_" + tag + ".png", out.mask);
  }
}

// Times the default setting alone (no reference render): wall and process CPU seconds per view.
void time_default(int views) {
  const Camera cam = bench_camera(false, "000");
  const Image img = bench_image();
  LensDropletRenderer r(bench_spec(4, false), kSeed, cam);
  r.render(img, cam, 0.0);  // warm-up (Embree and TBB start-up)
  const auto w0 = std::chrono::steady_clock::now();
  const std::clock_t c0 = std::clock();
  int64_t rays = 0;
  for (int i = 0; i < views; ++i) rays += r.render(img, cam, 0.0).embree_rays;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count() / views;
  const double cpu = double(std::clock() - c0) / CLOCKS_PER_SEC / views;
  std::printf("default view 600x400, 60 drops, 4 spp: %.1f ms wall, %.1f ms CPU, %.2f Mrays/s wall, "
              "%.2f Mrays/s per CPU second\n",
              1e3 * wall, 1e3 * cpu, rays / views / wall / 1e6, rays / views / cpu / 1e6);
}

}  // namespace
}  // namespace weathergs::generator::lens

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strncmp(argv[i], "--time_default=", 15) == 0) {
      weathergs::generator::lens::time_default(std::atoi(argv[i] + 15));
      return 0;
    }
    if (std::strncmp(argv[i], "--dump=", 7) == 0) {
      weathergs::generator::lens::dump(argv[i] + 7);
      return 0;
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
