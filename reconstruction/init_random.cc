#include "reconstruction/init_random.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/error.h"
#include "core/parallel.h"
#include "core/rng.h"

namespace weathergs::reconstruction {

namespace {

constexpr uint64_t kStreamRandomInit = 0x696e6974ull;  // the trainer's stream for initialization
// A view counts as seeing a depth hypothesis when at least this many of the 5 cross pixels land on
// valid pixels of it; a hypothesis needs min(2, K) such views (one neighbour would let a single
// chance match decide).
constexpr int kMinCrossPixels = 3;
constexpr double kCrossOffsetPx = 2.0;

// Bilinear sRGB sample at pixel coordinates (u, v) (pixel centres at +0.5); false outside the image
// or on a masked-out pixel.
bool sample_view(const TrainView& v, double u, double vv, Eigen::Vector3d* out) {
  const int w = v.camera.width, h = v.camera.height;
  const double x = u - 0.5, y = vv - 0.5;
  if (!(x >= 0 && y >= 0 && x <= w - 1 && y <= h - 1)) return false;
  const int x0 = std::min(int(x), std::max(w - 2, 0)), y0 = std::min(int(y), std::max(h - 2, 0));
  const int x1 = std::min(x0 + 1, w - 1), y1 = std::min(y0 + 1, h - 1);
  if (!v.invalid.empty()) {
    const int nx = std::clamp(int(std::lround(x)), 0, w - 1), ny = std::clamp(int(std::lround(y)), 0, h - 1);
    if (v.invalid[size_t(ny) * w + nx]) return false;
  }
  const double fx = x - x0, fy = y - y0;
  auto px = [&](int xx, int yy, int c) { return double(v.rgb[(size_t(yy) * w + xx) * 3 + c]); };
  for (int c = 0; c < 3; ++c)
    (*out)[c] = (1 - fy) * ((1 - fx) * px(x0, y0, c) + fx * px(x1, y0, c)) +
                fy * ((1 - fx) * px(x0, y1, c) + fx * px(x1, y1, c));
  return true;
}

// Per view, the K other views with the nearest camera centres (ties by index).
std::vector<std::vector<int>> nearest_views(const std::vector<TrainView>& views, int k) {
  const int n = int(views.size());
  std::vector<std::vector<int>> out(n);
  for (int i = 0; i < n; ++i) {
    std::vector<int> others;
    for (int j = 0; j < n; ++j)
      if (j != i) others.push_back(j);
    const Eigen::Vector3d ci = views[i].camera.center_world();
    std::stable_sort(others.begin(), others.end(), [&](int a, int b) {
      return (views[a].camera.center_world() - ci).squaredNorm() < (views[b].camera.center_world() - ci).squaredNorm();
    });
    others.resize(std::min<size_t>(others.size(), size_t(k)));
    out[i] = others;
  }
  return out;
}

}  // namespace

void sample_random_points(const std::vector<TrainView>& views, const TrainOptions& o,
                          std::vector<Eigen::Vector3d>* points, std::vector<Eigen::Vector3d>* colors) {
  WGS_CHECK(!views.empty());
  const int count = o.random_init_count;
  const double near_m = o.random_init_near_m, far_m = o.random_init_far_m;
  WGS_CHECK_GT(count, 0);
  WGS_CHECK(near_m > 0 && far_m > near_m);
  points->assign(size_t(count), Eigen::Vector3d::Zero());
  colors->assign(size_t(count), Eigen::Vector3d::Zero());
  const uint32_t n = uint32_t(views.size());
  const double inv_far = 1.0 / far_m, inv_span = 1.0 / near_m - 1.0 / far_m;

  if (o.random_init == TrainOptions::RandomInit::kFrustum) {
    // Uniform over the train views' frusta, uniform in inverse depth, random colours (the same draws
    // as before the photo-consistent mode existed: old runs keep their cloud).
    for (int i = 0; i < count; ++i) {
      Rng rng(o.seed, kStreamRandomInit, uint64_t(i));
      const Camera& cam = views[rng.uniform_int(n)].camera;
      const Eigen::Vector2d uv(cam.width * rng.uniform_double(), cam.height * rng.uniform_double());
      const double inv = inv_far + inv_span * rng.uniform_double();
      (*points)[i] = cam.unproject(uv, 1.0 / inv);
      for (int k = 0; k < 3; ++k) (*colors)[i][k] = rng.uniform_double();
    }
    return;
  }

  for (const TrainView& v : views)
    WGS_CHECK_EQ(v.rgb.size(), size_t(v.camera.width) * v.camera.height * 3);
  const std::vector<std::vector<int>> neighbors = nearest_views(views, kPlaneSweepNeighbors);
  const std::array<Eigen::Vector2d, 5> cross = {Eigen::Vector2d(0, 0), Eigen::Vector2d(kCrossOffsetPx, 0),
                                                Eigen::Vector2d(-kCrossOffsetPx, 0), Eigen::Vector2d(0, kCrossOffsetPx),
                                                Eigen::Vector2d(0, -kCrossOffsetPx)};
  constexpr int kPixelTries = 8;  // redraws of a masked-out pixel before taking it anyway
  parallel_for_chunks(0, count, 1024, [&](int64_t, int64_t lo, int64_t hi) {
    for (int64_t i = lo; i < hi; ++i) {
      Rng rng(o.seed, kStreamRandomInit, uint64_t(i));
      const int a = int(rng.uniform_int(n));
      const TrainView& va = views[a];
      const Camera& ca = va.camera;
      Eigen::Vector2d uv;
      std::array<Eigen::Vector3d, 5> ref;
      std::array<bool, 5> has_ref{};
      for (int t = 0; t < kPixelTries; ++t) {
        uv = Eigen::Vector2d(ca.width * rng.uniform_double(), ca.height * rng.uniform_double());
        for (int c = 0; c < 5; ++c) has_ref[c] = sample_view(va, uv.x() + cross[c].x(), uv.y() + cross[c].y(), &ref[c]);
        if (has_ref[0]) break;
      }
      const double jitter = rng.uniform_double();
      const std::vector<int>& nb = neighbors[a];
      const int min_views = std::min<int>(2, int(nb.size()));
      double best = std::numeric_limits<double>::infinity();
      int best_s = -1;
      Eigen::Vector3d best_color = has_ref[0] ? ref[0] : Eigen::Vector3d(0.5, 0.5, 0.5);
      if (has_ref[0] && min_views > 0) {
        for (int s = 0; s < kPlaneSweepDepths; ++s) {
          const double depth = 1.0 / (inv_far + inv_span * (s + jitter) / kPlaneSweepDepths);
          std::array<Eigen::Vector3d, 5> xs;
          for (int c = 0; c < 5; ++c) xs[c] = ca.unproject(uv + cross[c], depth);
          double err = 0;
          int seen = 0;
          Eigen::Vector3d color_sum = ref[0];
          for (int b : nb) {
            const TrainView& vb = views[b];
            double e = 0;
            int m = 0;
            Eigen::Vector3d center(0, 0, 0);
            bool has_center = false;
            for (int c = 0; c < 5; ++c) {
              if (!has_ref[c]) continue;
              const Eigen::Vector3d pc = vb.camera.to_camera(xs[c]);
              if (!(pc.z() > 1e-6)) continue;
              const Eigen::Vector2d p = vb.camera.project_camera(pc);
              Eigen::Vector3d col;
              if (!sample_view(vb, p.x(), p.y(), &col)) continue;
              e += (col - ref[c]).squaredNorm();
              ++m;
              if (c == 0) center = col, has_center = true;
            }
            if (m < kMinCrossPixels) continue;
            err += e / m;
            ++seen;
            if (has_center) color_sum += center;
            else color_sum += ref[0];
          }
          if (seen < min_views) continue;
          const double score = err / seen;
          if (score < best) {  // strict: on ties the farther depth (lower s) stays
            best = score;
            best_s = s;
            best_color = color_sum / double(seen + 1);
          }
        }
      }
      const int s = best_s >= 0 ? best_s : int(rng.uniform_int(uint32_t(kPlaneSweepDepths)));
      (*points)[i] = ca.unproject(uv, 1.0 / (inv_far + inv_span * (s + jitter) / kPlaneSweepDepths));
      (*colors)[i] = best_color;
    }
  });
}

GaussianSet<float> init_random(const std::vector<TrainView>& views, const TrainOptions& options) {
  std::vector<Eigen::Vector3d> points, colors;
  sample_random_points(views, options, &points, &colors);
  return init_from_points(points, colors);
}

}  // namespace weathergs::reconstruction
