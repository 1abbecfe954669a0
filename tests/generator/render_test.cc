// The streak renderer on synthetic single particles whose answer is known.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "generator/render.h"

namespace weathergs::generator {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

struct ViewSetup {
  Camera camera;
  Image depth;
  RenderOptions options;
  RenderView view() const {
    RenderView v;
    v.camera = camera;
    v.depth = &depth;
    v.lens = options.defocus ? thin_lens_of(camera) : std::nullopt;
    return v;
  }
};

// Camera at the world origin with world = camera axes (identity pose).
ViewSetup make_setup(int w = 200, int h = 120, double f = 500, double exposure = 0.02, float background = kInf) {
  ViewSetup s;
  s.camera.name = "v";
  s.camera.width = w, s.camera.height = h;
  s.camera.fx = s.camera.fy = f;
  s.camera.cx = w / 2.0, s.camera.cy = h / 2.0;
  s.camera.exposure_s = exposure;
  s.depth = Image(w, h, 1, ColorSpace::kLinear, background);
  s.options.visibility_cutoff = 1e-9;  // draw everything in these tests
  return s;
}

// Renders one particle moving linearly p0 + v t over the exposure.
ParticleRaster render_one(const ViewSetup& s, const Eigen::Vector3d& p0, const Eigen::Vector3d& v, double radius_m,
                          double opacity = 1.0, bool* drawn = nullptr) {
  const std::vector<double> times = path_sample_times(s.options, 0.0, s.camera.exposure_s);
  std::vector<Eigen::Vector3d> pos;
  for (double t : times) pos.push_back(p0 + v * t);
  SplatList list;
  const RenderView view = s.view();
  const bool ok = add_splat(view, s.options, pos.data(), int(pos.size()), radius_m, opacity, 0, &list);
  if (drawn) *drawn = ok;
  for (Splat& sp : list.splats) sp.radiance = Eigen::Vector3f(1, 1, 1);
  return rasterize_splats(view, list, s.options);
}

double alpha_sum(const ParticleRaster& r) { return std::accumulate(r.alpha.data.begin(), r.alpha.data.end(), 0.0); }

// Streak length measured from the alpha image of a thin horizontal streak in one pixel row: the
// mass divided by the mean alpha of the fully crossed pixels (all but the two end pixels), since
// the streak deposits mass / L per pixel of length.
double measured_length_px(const ParticleRaster& r) {
  std::vector<float> nz;
  for (float a : r.alpha.data)  // row-major: one row, left to right
    if (a > 0) nz.push_back(a);
  if (nz.size() < 3) return 0;
  const double interior = std::accumulate(nz.begin() + 1, nz.end() - 1, 0.0) / double(nz.size() - 2);
  return alpha_sum(r) / interior;
}

TEST(Render, StreakLengthIsFocalTimesPerpendicularSpeedTimesExposureOverDepth) {
  // The required tolerance: 2%.
  constexpr double kLengthTolerance = 0.02;
  for (StreakMode mode : {StreakMode::kAnalytic, StreakMode::kTimeSamples}) {
    for (double z : {3.0, 5.0, 8.0}) {
      ViewSetup s = make_setup();
      s.options.streak = mode;
      s.options.time_samples = 256;
      const Eigen::Vector3d v(6.0, 0, 0);
      const double expected = s.camera.fx * v.norm() * s.camera.exposure_s / z;  // 6..20 px
      // Start so that the streak sits inside a pixel row, away from row boundaries.
      const ParticleRaster r = render_one(s, Eigen::Vector3d(-0.3 * z / 5, 0.0101 * z / 5, z), v, 1e-4);
      EXPECT_NEAR(measured_length_px(r) / expected, 1.0, kLengthTolerance)
          << "mode " << int(mode) << " z " << z << " expected " << expected;
    }
  }
}

TEST(Render, ThinStreakConservesItsMass) {
  ViewSetup s = make_setup();
  const double radius = 2e-4, z = 4.0;
  const ParticleRaster r = render_one(s, Eigen::Vector3d(0.1, -0.2, z), Eigen::Vector3d(3, 5, 0), radius, 0.7);
  const double rpx = s.camera.fx * radius / z;
  // Float accumulation over ~40 pixels: 1e-5 relative.
  EXPECT_NEAR(alpha_sum(r), 0.7 * M_PI * rpx * rpx, 1e-5 * 0.7 * M_PI * rpx * rpx + 1e-9);
}

TEST(Render, AnalyticCoverageMatchesManyTimeSamples) {
  // A wide (disk-kernel) and a thin (point-kernel) streak: 1024 time samples converge to the
  // analytic coverage; the residual is the dots' discreteness, ~1/1024 of the mass per pixel.
  for (double radius : {1e-4, 4e-3}) {
    ViewSetup a = make_setup();
    ViewSetup b = make_setup();
    b.options.streak = StreakMode::kTimeSamples;
    b.options.time_samples = 1024;
    const Eigen::Vector3d p0(-0.05, 0.02, 3.0), v(4, 2, 0);
    const ParticleRaster ra = render_one(a, p0, v, radius), rb = render_one(b, p0, v, radius);
    double max_diff = 0, peak = 0;
    for (size_t i = 0; i < ra.alpha.data.size(); ++i) {
      max_diff = std::max(max_diff, double(std::abs(ra.alpha.data[i] - rb.alpha.data[i])));
      peak = std::max(peak, double(ra.alpha.data[i]));
    }
    EXPECT_LT(max_diff, 0.02 * peak + 1e-6) << radius;
    EXPECT_NEAR(alpha_sum(ra), alpha_sum(rb), 0.01 * alpha_sum(ra)) << radius;
  }
}

// Alpha-weighted mean x of a raster.
double centroid_x(const ParticleRaster& r) {
  double m = 0, mx = 0;
  for (int y = 0; y < r.alpha.height; ++y)
    for (int x = 0; x < r.alpha.width; ++x) {
      m += r.alpha.at(x, y);
      mx += r.alpha.at(x, y) * (x + 0.5);
    }
  return mx / m;
}

TEST(Render, OneSegmentFollowsPerspectiveAlongTheStreak) {
  // A drop receding from 0.3 to 0.6 m while crossing the view. Its image moves as f X / Z, fast at
  // the near end, and its footprint shrinks as 1 / Z^2: per pixel of path the two cancel, but the
  // total is opacity pi (f r)^2 / (Z0 Z1) (the mean of 1 / Z^2 over the exposure for Z linear in
  // time), 20% less than one constant-speed primitive with the ends' mean footprint deposits
  // ((1/Z0^2 + 1/Z1^2) / 2). One analytic segment per exposure must match 256 segments and that
  // integral (its primitives subdivide the segment for perspective).
  const Eigen::Vector3d p0(-0.05, 0.001, 0.3), v(6, 0, 15);
  const double z0 = p0.z(), z1 = p0.z() + 0.02 * v.z(), f = 500;
  for (double radius : {1e-4, 1e-3}) {  // point kernel (0.17 px) and disk kernel (1.7 px at 0.3 m)
    ViewSetup one = make_setup(), many = make_setup();
    many.options.segments = 256;
    const ParticleRaster r1 = render_one(one, p0, v, radius), rn = render_one(many, p0, v, radius);
    double max_diff = 0, peak = 0;
    for (size_t i = 0; i < r1.alpha.data.size(); ++i) {
      max_diff = std::max(max_diff, double(std::abs(r1.alpha.data[i] - rn.alpha.data[i])));
      peak = std::max(peak, double(rn.alpha.data[i]));
    }
    // Tolerances: the subdivision keeps each primitive's mid-time error below 0.1 px; 3% of the peak
    // per pixel and 0.25 px of centroid leave room for the disk kernel's lattice (<= 2% of its area).
    EXPECT_LT(max_diff, 0.03 * peak) << radius;
    EXPECT_NEAR(centroid_x(r1), centroid_x(rn), 0.25) << radius;
    const double mass = M_PI * f * radius * f * radius / (z0 * z1);
    const double chord_mass = M_PI * f * radius * f * radius * 0.5 * (1 / (z0 * z0) + 1 / (z1 * z1));
    ASSERT_GT(chord_mass, 1.2 * mass);  // the case is sensitive
    EXPECT_NEAR(alpha_sum(r1), mass, 0.02 * mass) << radius;
  }
}

TEST(Render, ParticleBehindGeometryIsInvisible) {
  ViewSetup s = make_setup();
  s.depth = Image(s.camera.width, s.camera.height, 1, ColorSpace::kLinear, 4.0f);
  EXPECT_EQ(alpha_sum(render_one(s, Eigen::Vector3d(0, 0, 5), Eigen::Vector3d(1, 0, 0), 1e-3)), 0.0);
  EXPECT_GT(alpha_sum(render_one(s, Eigen::Vector3d(0, 0, 3), Eigen::Vector3d(1, 0, 0), 1e-3)), 0.0);
  // A background of 65504 or 1e10 hides nothing.
  for (float bg : {65504.0f, 1e10f, kInf}) {
    ViewSetup t = make_setup(200, 120, 500, 0.02, bg);
    EXPECT_GT(alpha_sum(render_one(t, Eigen::Vector3d(0, 0, 30), Eigen::Vector3d(1, 0, 0), 1e-3)), 0.0) << bg;
  }
}

TEST(Render, HardCasesStayFinite) {
  auto finite_and_bounded = [](const ParticleRaster& r) {
    for (float a : r.alpha.data)
      if (!(std::isfinite(a) && a >= 0 && a <= 1)) return false;
    for (float a : r.radiance.data)
      if (!std::isfinite(a)) return false;
    return true;
  };
  ViewSetup s = make_setup();
  bool drawn = true;
  // At the camera center and behind the camera: nothing to draw.
  EXPECT_TRUE(finite_and_bounded(render_one(s, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 1e-3, 1, &drawn)));
  EXPECT_FALSE(drawn);
  EXPECT_TRUE(finite_and_bounded(render_one(s, Eigen::Vector3d(0, 0, -2), Eigen::Vector3d(1, 0, 0), 1e-3, 1, &drawn)));
  EXPECT_FALSE(drawn);
  // Crossing the near plane during the exposure: clipped, drawn, finite.
  const ParticleRaster cross = render_one(s, Eigen::Vector3d(0.01, 0, -0.5), Eigen::Vector3d(0, 0, 60), 1e-3, 1, &drawn);
  EXPECT_TRUE(drawn);
  EXPECT_TRUE(finite_and_bounded(cross));
  // Moving along the view ray: a zero-length streak, all its mass in one pixel.
  const Eigen::Vector3d p(0.0101, 0.0102, 4.0);
  const ParticleRaster ray = render_one(s, p, p.normalized() * 0.0, 1e-4);
  int nonzero = 0;
  for (float a : ray.alpha.data) nonzero += a > 0;
  EXPECT_EQ(nonzero, 1);
  const ParticleRaster along = render_one(s, p, p.normalized() * 5.0, 1e-4);
  EXPECT_TRUE(finite_and_bounded(along));
  // Exposure 0 and 1 s with 60 m/s wind; a one-pixel image.
  for (double exposure : {0.0, 1.0}) {
    ViewSetup e = make_setup(200, 120, 500, exposure);
    EXPECT_TRUE(finite_and_bounded(render_one(e, Eigen::Vector3d(-10, 0, 2), Eigen::Vector3d(60, 0, -9), 3e-3)));
  }
  ViewSetup one = make_setup(1, 1, 1.0);
  EXPECT_TRUE(finite_and_bounded(render_one(one, Eigen::Vector3d(0, 0, 0.2), Eigen::Vector3d(0, -9, 0), 3e-3)));
}

TEST(Render, DefocusSpreadsNearParticlesIntoSoftDiscs) {
  ViewSetup sharp = make_setup(200, 120, 500, 0.0);
  ViewSetup blur = sharp;
  blur.camera.f_number = 2.0, blur.camera.focal_length_mm = 35, blur.camera.focus_distance_m = 10;
  const Eigen::Vector3d p(0.0, 0.0, 0.5);
  const ParticleRaster a = render_one(sharp, p, Eigen::Vector3d::Zero(), 2e-3);  // R = 2 px
  const ParticleRaster b = render_one(blur, p, Eigen::Vector3d::Zero(), 2e-3);
  const double coc = thin_lens_of(blur.camera)->coc_radius_px(500, 0.5);
  // CoC radius: 500 px * (17.5 mm aperture) * 9.5 m / (2 * 0.5 m * 9.965 m) = 8.34 px.
  EXPECT_NEAR(coc, 500 * 0.0175 * 9.5 / (2 * 0.5 * 9.965), 1e-9);
  const double peak_a = *std::max_element(a.alpha.data.begin(), a.alpha.data.end());
  const double peak_b = *std::max_element(b.alpha.data.begin(), b.alpha.data.end());
  EXPECT_LT(peak_b, 0.1 * peak_a);  // soft
  int wide = 0;
  for (float v : b.alpha.data) wide += v > 0;
  EXPECT_GT(wide, int(M_PI * coc * coc * 0.8));  // large
  // The mass (alpha x area = pi R_drop^2) is conserved by the blur. The disk kernel counts >= 16
  // points per radius here: lattice-counting error of the area below 2%.
  const double mass = M_PI * std::pow(500 * 2e-3 / 0.5, 2);
  EXPECT_NEAR(alpha_sum(a) / mass, 1.0, 0.02);
  EXPECT_NEAR(alpha_sum(b) / mass, 1.0, 0.02);
}

TEST(Render, RenderOptionsValidation) {
  RenderOptions o;
  EXPECT_NO_THROW(o.validate("spec"));
  o.segments = 0;
  EXPECT_THROW(o.validate("spec"), InputError);
  o = RenderOptions();
  o.visibility_cutoff = 0;
  EXPECT_THROW(o.validate("spec"), InputError);
}

}  // namespace
}  // namespace weathergs::generator
