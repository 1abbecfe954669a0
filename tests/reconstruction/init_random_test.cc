// Random initialization without SfM points (reconstruction/init_random.h) on a forward-facing rig:
// the photo-consistent mode puts points on the surfaces, the frustum mode fills the frusta.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/parallel.h"
#include "reconstruction/init_random.h"
#include "reconstruction/loss.h"
#include "tests/reconstruction/test_scene.h"

namespace weathergs::reconstruction {
namespace {

using testing::look_at_camera;

// A street seen by a sliding rig: a back wall at y = 8 m and a ground plane at z = 0, both with a
// smooth texture that never repeats within the views; cameras 1.5 m above the ground, looking along
// +y, spaced 0.25 m along x (forward-facing, like a dolly shot of our scenes).
struct Street {
  static constexpr double kWallY = 8.0;
  static constexpr double kEyeZ = 1.5;

  static Eigen::Vector3d texture(double u, double v) {
    const double a = 0.5 + 0.25 * std::sin(3.1 * u + 0.7 * std::sin(1.3 * v)) + 0.2 * std::sin(7.3 * v + 1.9 * u);
    const double b = 0.5 + 0.45 * std::sin(5.7 * u - 2.3 * v) * std::cos(4.1 * v);
    return Eigen::Vector3d(std::clamp(a, 0.0, 1.0), std::clamp(0.3 + 0.5 * b, 0.0, 1.0), std::clamp(0.8 - 0.5 * a * b, 0.0, 1.0));
  }

  // Ray cast of pixel (x + 0.5, y + 0.5): colour and planar depth (camera z).
  static Eigen::Vector3d shade(const Camera& cam, double u, double v, double* depth) {
    const Eigen::Vector3d o = cam.center_world(), d = cam.ray_direction_world(Eigen::Vector2d(u, v));
    double t = std::numeric_limits<double>::infinity();
    Eigen::Vector3d col(0.6, 0.75, 0.95);  // sky
    if (d.y() > 1e-9) {
      const double tw = (kWallY - o.y()) / d.y();
      const Eigen::Vector3d p = o + tw * d;
      if (p.z() >= 0) t = tw, col = texture(p.x(), p.z());
    }
    if (d.z() < -1e-9) {
      const double tg = -o.z() / d.z();
      if (tg < t) t = tg, col = 0.7 * texture(0.8 * (o + tg * d).x() + 5.0, 0.8 * (o + tg * d).y());
    }
    *depth = std::isfinite(t) ? cam.to_camera(o + t * d).z() : std::numeric_limits<double>::infinity();
    return col;
  }

  static std::vector<TrainView> views(int count, int width, int height) {
    std::vector<TrainView> out;
    for (int i = 0; i < count; ++i) {
      const double x = 0.25 * (i - (count - 1) / 2.0);
      TrainView v;
      v.camera = look_at_camera("v" + std::to_string(i), width, height, 0.8 * width, Eigen::Vector3d(x, 0, kEyeZ),
                                Eigen::Vector3d(x, 10, kEyeZ - 0.6));
      v.rgb.resize(size_t(width) * height * 3);
      for (int y = 0; y < height; ++y)
        for (int xx = 0; xx < width; ++xx) {
          double depth;
          const Eigen::Vector3d c = shade(v.camera, xx + 0.5, y + 0.5, &depth);
          for (int k = 0; k < 3; ++k) v.rgb[(size_t(y) * width + xx) * 3 + k] = float(c[k]);
        }
      out.push_back(std::move(v));
    }
    return out;
  }

  // Distance (m) of a point to the nearest surface (wall or ground).
  static double surface_distance(const Eigen::Vector3d& p) {
    const double wall = p.z() >= 0 ? std::abs(p.y() - kWallY) : std::hypot(p.y() - kWallY, p.z());
    const double ground = p.y() <= kWallY ? std::abs(p.z()) : std::hypot(p.y() - kWallY, p.z());
    return std::min(wall, ground);
  }
};

TrainOptions init_options(TrainOptions::RandomInit mode, int count) {
  TrainOptions o;
  o.random_init = mode;
  o.random_init_count = count;
  o.seed = 5;
  return o;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

TEST(RandomInitTest, PhotoConsistentPointsLieOnTheSurfacesFrustumPointsDoNot) {
  const std::vector<TrainView> views = Street::views(10, 96, 64);
  std::vector<Eigen::Vector3d> pts, cols, pts_f, cols_f;
  sample_random_points(views, init_options(TrainOptions::RandomInit::kPhotoConsistent, 3000), &pts, &cols);
  sample_random_points(views, init_options(TrainOptions::RandomInit::kFrustum, 3000), &pts_f, &cols_f);
  std::vector<double> d, d_f;
  for (size_t i = 0; i < pts.size(); ++i) {
    ASSERT_TRUE(pts[i].allFinite() && cols[i].allFinite()) << i;
    d.push_back(Street::surface_distance(pts[i]));
  }
  for (const Eigen::Vector3d& p : pts_f) d_f.push_back(Street::surface_distance(p));
  const double med = median(d), med_f = median(d_f);
  std::printf("median distance to the surfaces: photo %.3f m, frustum %.3f m\n", med, med_f);
  // Depth resolution of 48 inverse-depth strata over 0.5-20 m at the wall (8 m): ~0.7 m per stratum.
  EXPECT_LT(med, 0.5);
  EXPECT_GT(med_f, 1.0);
  EXPECT_LT(med, 0.4 * med_f);
  int close = 0;
  for (double x : d) close += x < 1.0;
  EXPECT_GT(close, int(0.7 * d.size()));
}

TEST(RandomInitTest, SameCloudWithOneAndTwoThreadsAndMaskedPixelsAreNeverUsed) {
  std::vector<TrainView> views = Street::views(6, 64, 48);
  const TrainOptions o = init_options(TrainOptions::RandomInit::kPhotoConsistent, 800);
  std::vector<Eigen::Vector3d> a, ca, b, cb;
  const int before = num_threads();
  set_num_threads(1);
  sample_random_points(views, o, &a, &ca);
  set_num_threads(2);
  sample_random_points(views, o, &b, &cb);
  set_num_threads(before);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i], b[i]) << i;
    EXPECT_EQ(ca[i], cb[i]) << i;
  }
  // A pure-red patch under a mask in every view (as a lens drop would be): never a point's colour.
  for (TrainView& v : views) {
    v.invalid.assign(size_t(v.camera.width) * v.camera.height, 0);
    for (int y = 10; y < 30; ++y)
      for (int x = 20; x < 44; ++x) {
        const size_t p = size_t(y) * v.camera.width + x;
        v.invalid[p] = 1;
        v.rgb[p * 3] = 1.f, v.rgb[p * 3 + 1] = 0.f, v.rgb[p * 3 + 2] = 0.f;
      }
  }
  sample_random_points(views, o, &a, &ca);
  for (size_t i = 0; i < a.size(); ++i) EXPECT_FALSE(ca[i].x() > 0.9 && ca[i].y() < 0.1 && ca[i].z() < 0.1) << i;
}

TEST(RandomInitTest, DegenerateInputsGiveFiniteClouds) {
  // One view (no neighbour to compare with), a black image, a fully masked image.
  std::vector<TrainView> one = Street::views(1, 32, 24);
  std::vector<TrainView> dark = Street::views(3, 32, 24);
  for (TrainView& v : dark) std::fill(v.rgb.begin(), v.rgb.end(), 0.f);
  std::vector<TrainView> masked = Street::views(3, 32, 24);
  for (TrainView& v : masked) v.invalid.assign(size_t(32) * 24, 1);
  for (const auto* vs : {&one, &dark, &masked}) {
    const GaussianSet<float> g = init_random(*vs, init_options(TrainOptions::RandomInit::kPhotoConsistent, 200));
    ASSERT_EQ(g.size(), 200u);
    for (float x : g.position) ASSERT_TRUE(std::isfinite(x));
    for (float x : g.log_scale) ASSERT_TRUE(std::isfinite(x));
    for (float x : g.sh) ASSERT_TRUE(std::isfinite(x));
  }
}

// The gap this mode closes: a forward-facing scene without SfM points, trained from each initialization;
// test PSNR on held-out views between the train views.
TEST(RandomInitTest, TrainingFromThePhotoConsistentCloudReachesASensiblePsnr) {
  const int w = 48, h = 32;
  std::vector<TrainView> all = Street::views(13, w, h);
  std::vector<TrainView> train, test;
  for (size_t i = 0; i < all.size(); ++i) (i % 4 == 2 ? test : train).push_back(all[i]);
  auto test_psnr = [&](TrainOptions::RandomInit mode) {
    TrainOptions o = init_options(mode, 3000);
    o.iterations = 400;
    std::vector<Camera> cams;
    for (const TrainView& v : train) cams.push_back(v.camera);
    Trainer t(train, init_random(train, o), o, scene_extent(cams));
    while (t.iteration() < o.iterations) t.step();
    double mse = 0;
    for (const TrainView& v : test) {
      RasterState<float> st;
      rasterize_forward(t.gaussians(), RasterCamera<float>::from(v.camera), RasterSettings<float>{}, &st);
      for (size_t k = 0; k < v.rgb.size(); ++k) {
        const double e = std::clamp(st.image[k], 0.f, 1.f) - v.rgb[k];
        mse += e * e / double(v.rgb.size() * test.size());
      }
    }
    return psnr_from_mse(mse);
  };
  const double photo = test_psnr(TrainOptions::RandomInit::kPhotoConsistent);
  const double frustum = test_psnr(TrainOptions::RandomInit::kFrustum);
  std::printf("test PSNR after 400 iterations: photo-consistent init %.2f dB, frustum init %.2f dB\n", photo, frustum);
  EXPECT_GT(photo, frustum + 2.0);
  EXPECT_GT(photo, 24.0);
}

}  // namespace
}  // namespace weathergs::reconstruction
