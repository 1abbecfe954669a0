// The radiance field (nerf/field.h): the backward pass against central finite differences, exact
// empty-space skipping, save/load, resampling, extreme values, non-forward-facing captures and the
// near plane from SfM points.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "core/rng.h"
#include "nerf/field.h"
#include "nerf/frustum.h"
#include "tests/core/test_util.h"

namespace weathergs::nerf {
namespace {

using weathergs::testing::TempDir;

// Three cameras side by side looking down world +z (camera axes = world axes).
std::vector<Camera> cameras(int n = 3, int w = 24, int h = 16) {
  std::vector<Camera> cams;
  for (int i = 0; i < n; ++i) {
    Camera c;
    c.name = "c" + std::to_string(i);
    c.width = w, c.height = h;
    c.fx = c.fy = 20;
    c.cx = w / 2.0, c.cy = h / 2.0;
    c.camera_from_world.setIdentity();
    c.camera_from_world(0, 3) = -0.3 * (i - 1);
    cams.push_back(c);
  }
  return cams;
}

RadianceField random_field(const GridDims& dims, uint64_t seed, float raw_lo, float raw_hi) {
  RadianceField f(forward_facing_frame(cameras(), 1.0), dims, 0.05);
  Rng rng(seed, 0, 0);
  for (int64_t p = 0; p < dims.points(); ++p) {
    f.params()[size_t(p) * kStride] = rng.uniform(raw_lo, raw_hi);
    for (int q = 1; q <= 3 * kShCoeffs; ++q) f.params()[size_t(p) * kStride + q] = rng.uniform(-1.5f, 1.5f);
  }
  for (float& e : f.env()) e = rng.uniform(-2.f, 2.f);
  f.rebuild_occupancy();
  return f;
}

// Smooth everywhere: no sample is dropped, the march never stops early.
MarchSettings exact_march() {
  MarchSettings s;
  s.min_weight = 0;
  s.min_transmittance = 0;
  s.use_occupancy = false;
  return s;
}

// L = sum_rays a . C(ray); its gradient with respect to every parameter, by the backward pass.
double loss(const RadianceField& f, const std::vector<Ray>& rays, const std::vector<std::array<float, 3>>& a) {
  double l = 0;
  for (size_t r = 0; r < rays.size(); ++r) {
    const RayResult res = f.march(rays[r], 0.37f, exact_march(), nullptr);
    for (int ch = 0; ch < 3; ++ch) l += double(a[r][ch]) * res.rgb[ch];
  }
  return l;
}

TEST(FieldTest, BackwardMatchesFiniteDifferences) {
  const GridDims dims{5, 4, 6};
  RadianceField f = random_field(dims, 7, -3.f, 1.5f);
  const std::vector<Camera> cams = cameras();
  std::vector<Ray> rays;
  std::vector<std::array<float, 3>> a;
  Rng rng(3, 0, 0);
  for (int r = 0; r < 12; ++r) {
    const Camera& c = cams[size_t(r % 3)];
    rays.push_back(pixel_ray(c, int(rng.uniform_int(uint32_t(c.width))), int(rng.uniform_int(uint32_t(c.height)))));
    a.push_back({rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)});
  }
  std::vector<float> grad(f.params().size(), 0.f), env_grad(f.env().size(), 0.f);
  std::vector<uint8_t> touched(size_t(dims.points()), 0);
  int64_t samples_total = 0;
  for (size_t r = 0; r < rays.size(); ++r) {
    std::vector<RaySample> samples;
    const RayResult res = f.march(rays[r], 0.37f, exact_march(), &samples);
    samples_total += int64_t(samples.size());
    std::vector<SampleGrad> grads;
    float eg[3];
    f.march_backward(samples, res, a[r].data(), &grads, eg);
    for (const SampleGrad& sg : grads) spread_sample_grad(sg, dims, 0, dims.nw, grad.data(), touched.data());
    int idx[4];
    float w[4];
    f.env_taps(rays[r].direction, idx, w);
    for (int q = 0; q < 4; ++q)
      for (int ch = 0; ch < 3; ++ch) env_grad[size_t(idx[q]) * 3 + ch] += w[q] * eg[ch];
  }
  ASSERT_GT(samples_total, 100);
  // Central differences with h = 1e-2 on a float32 march: the loss (~1) is rounded to ~6e-8 per
  // ray, so the quotient carries up to ~12 x 6e-8 / 2e-2 ~ 4e-5 of noise, typically ~1e-6 (the
  // spread measured on this field); truncation is O(h^2), relative. The gradients are 1e-6..1e-3.
  constexpr float kH = 1e-2f;
  constexpr double kAbsTol = 1e-5, kRelTol = 3e-2;
  // The central difference of the loss in one value, checked against its analytic gradient.
  auto check = [&](float& x, double analytic, const std::string& what) {
    const float x0 = x;
    x = x0 + kH;
    const double lp = loss(f, rays, a);
    x = x0 - kH;
    const double lm = loss(f, rays, a);
    x = x0;
    const double fd = (lp - lm) / (2 * kH);
    EXPECT_NEAR(analytic, fd, kAbsTol + kRelTol * std::abs(fd)) << what;
  };
  int checked = 0;
  for (int64_t p = 0; p < dims.points(); ++p) {
    if (!touched[size_t(p)]) continue;
    for (int q = 0; q <= 3 * kShCoeffs; q += (q == 0 ? 1 : 5), ++checked)  // density and 3 colour coefficients
      check(f.params()[size_t(p) * kStride + q], grad[size_t(p) * kStride + q],
            "point " + std::to_string(p) + " param " + std::to_string(q));
  }
  EXPECT_GT(checked, 50);
  for (size_t q = 0; q < f.env().size(); q += 7) check(f.env()[q], env_grad[q], "env " + std::to_string(q));
}

TEST(FieldTest, EmptySpaceSkippingIsExact) {
  // Mostly empty (raw far below the activity threshold) with a few dense blobs.
  const GridDims dims{12, 9, 14};
  RadianceField f = random_field(dims, 11, -30.f, -25.f);
  Rng rng(5, 0, 0);
  for (int n = 0; n < 40; ++n) f.params()[size_t(rng.uniform_int(uint32_t(dims.points()))) * kStride] = rng.uniform(-2, 4);
  f.rebuild_occupancy();
  EXPECT_LT(f.occupied_cells(), dims.cells() / 2);
  const Camera cam = cameras()[1];
  MarchSettings on, off;
  off.use_occupancy = false;
  EXPECT_EQ(f.render(cam, on), f.render(cam, off));  // bit for bit
  // Incremental updates agree with a rebuild.
  RadianceField g = f;
  for (int n = 0; n < 200; ++n) {
    const int64_t p = rng.uniform_int(uint32_t(dims.points()));
    float& raw = g.params()[size_t(p) * kStride];
    const bool was = raw >= g.active_raw();
    raw = rng.uniform(-30, 3);
    g.update_occupancy(p, was, raw >= g.active_raw());
  }
  const int64_t incremental = g.occupied_cells();
  g.rebuild_occupancy();
  EXPECT_EQ(incremental, g.occupied_cells());
}

TEST(FieldTest, ExtremeValuesStayFinite) {
  const GridDims dims{6, 5, 7};
  for (float raw : {-1e4f, -80.f, 0.f, 80.f, 1e4f}) {
    RadianceField f = random_field(dims, 2, raw, raw);
    for (int64_t p = 0; p < dims.points(); ++p)
      for (int q = 1; q <= 3 * kShCoeffs; ++q) f.params()[size_t(p) * kStride + q] = raw;
    f.rebuild_occupancy();
    std::vector<RaySample> samples;
    const RayResult r = f.march(pixel_ray(cameras()[0], 3, 4), 0.5f, MarchSettings{}, &samples);
    std::vector<SampleGrad> grads;
    float eg[3];
    const float g[3] = {1, -1, 0.5f};
    f.march_backward(samples, r, g, &grads, eg);
    for (float c : r.rgb) EXPECT_TRUE(std::isfinite(c) && c >= 0 && c <= 1) << raw;
    for (const SampleGrad& sg : grads) {
      EXPECT_TRUE(std::isfinite(sg.d_raw)) << raw;
      for (float d : sg.d_pre) EXPECT_TRUE(std::isfinite(d)) << raw;
    }
  }
}

TEST(FieldTest, SaveLoadRoundTripAndCorruptFiles) {
  TempDir tmp;
  const RadianceField f = random_field(GridDims{5, 4, 6}, 9, -3, 2);
  f.save(tmp / "field.bin");
  const RadianceField g = RadianceField::load(tmp / "field.bin");
  EXPECT_TRUE(g.dims() == f.dims());
  EXPECT_EQ(g.env(), f.env());
  const Camera cam = cameras()[2];
  EXPECT_EQ(g.render(cam, MarchSettings{}), f.render(cam, MarchSettings{}));
  // Truncated, missing, not a field.
  std::filesystem::resize_file(tmp / "field.bin", std::filesystem::file_size(tmp / "field.bin") - 8);
  EXPECT_THROW(RadianceField::load(tmp / "field.bin"), InputError);
  EXPECT_THROW(RadianceField::load(tmp / "missing.bin"), InputError);
  std::ofstream(tmp / "junk.bin") << "hello\n{}\n";
  EXPECT_THROW(RadianceField::load(tmp / "junk.bin"), InputError);
}

TEST(FieldTest, ResamplingKeepsTheField) {
  // A field linear in the grid coordinates is reproduced exactly by trilinear resampling.
  const GridDims dims{5, 4, 6};
  RadianceField f = random_field(dims, 1, 0, 0);
  for (int k = 0; k < dims.nw; ++k)
    for (int j = 0; j < dims.nv; ++j)
      for (int i = 0; i < dims.nu; ++i) f.params()[size_t(f.index(i, j, k)) * kStride] = 0.5f * i - 0.25f * j + 0.1f * k;
  const RadianceField g = f.resampled(GridDims{9, 7, 11});
  for (int k = 0; k < 11; ++k)
    for (int j = 0; j < 7; ++j)
      for (int i = 0; i < 9; ++i)
        EXPECT_NEAR(g.params()[size_t(g.index(i, j, k)) * kStride],
                    0.5f * i * 4 / 8.f - 0.25f * j * 3 / 6.f + 0.1f * k * 5 / 10.f, 1e-5);
}

TEST(FrustumTest, CoversEveryViewAndRejectsNonForwardFacing) {
  std::vector<Camera> cams = cameras();
  const FrustumFrame fr = forward_facing_frame(cams, 0.5);
  // Every pixel's ray, at every depth beyond near, falls inside the u/v bounds.
  RadianceField f(fr, GridDims{8, 8, 8}, 0.01);
  for (const Camera& c : cams)
    for (int y : {0, c.height - 1})
      for (int x : {0, c.width - 1})
        for (double z : {0.6, 2.0, 50.0}) {
          const Eigen::Vector3d g = f.grid_coords(c.center_world() + z * pixel_ray(c, x, y).direction);
          EXPECT_GE(g.x(), 0);
          EXPECT_LE(g.x(), 7);
          EXPECT_GE(g.y(), 0);
          EXPECT_LE(g.y(), 7);
        }
  // A camera turned around: a clear error naming it.
  cams[2].camera_from_world.topLeftCorner<3, 3>() = Eigen::Matrix3d(Eigen::AngleAxisd(3.0, Eigen::Vector3d::UnitY()));
  try {
    forward_facing_frame(cams, 0.5);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("c2"), std::string::npos) << e.what();
  }
  EXPECT_THROW(forward_facing_frame(cameras(), 0.0), InputError);
}

TEST(FrustumTest, NearPlaneIgnoresTwoViewPointsWhenEnoughAreChecked) {
  // 100 points seen by three views at 10-11 m, and two seen by two views 0.3 m in front of the cameras
  // (what falling snow matched across two views gives): the near plane is half the 1st-percentile
  // depth of the checked points, not of the stray ones.
  std::vector<ColmapPoint3D> sfm;
  for (int i = 0; i < 100; ++i) {
    ColmapPoint3D p;
    p.xyz = Eigen::Vector3d(0.01 * i - 0.5, 0.0, 10.0 + 0.01 * i);
    p.track = {{1, i}, {2, i}, {3, i}};
    sfm.push_back(p);
  }
  for (int i = 0; i < 2; ++i) {
    ColmapPoint3D p;
    p.xyz = Eigen::Vector3d(0.1 * i, 0.0, 0.3);
    p.track = {{1, 100 + i}, {2, 100 + i}};
    sfm.push_back(p);
  }
  const std::vector<Camera> cams = cameras();
  const std::vector<Eigen::Vector3d> checked = near_plane_points(sfm);
  EXPECT_EQ(checked.size(), 100u);
  EXPECT_NEAR(near_from_points(cams, checked, 0.05, 1.0), 0.5 * 10.01, 1e-9);
  std::vector<Eigen::Vector3d> all;
  for (const ColmapPoint3D& p : sfm) all.push_back(p.xyz);
  EXPECT_NEAR(near_from_points(cams, all, 0.05, 1.0), 0.15, 1e-9);  // what it was before
  // Fewer than 10 checked points: all of them count (a sparse model of two-view points only).
  for (ColmapPoint3D& p : sfm) p.track.resize(2);
  EXPECT_EQ(near_plane_points(sfm).size(), sfm.size());
}

}  // namespace
}  // namespace weathergs::nerf
