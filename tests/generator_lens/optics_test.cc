// Optics of the lens droplets: interface formulas against textbook values, and properties of paths
// through drops that hold exactly (apex ray, flat drop, inversion, Snell, energy).
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/rng.h"
#include "generator/lens/drop_scene.h"
#include "generator/lens/optics.h"
#include "tests/generator_lens/lens_test_util.h"

namespace weathergs::generator::lens {
namespace {

using testing::kDeg;
using testing::test_drop;
using testing::test_plane;
using Vec3 = Eigen::Vector3d;

// Direction identities computed in double: rounding is ~1e-16 per operation, a path has < 20.
constexpr double kDirTol = 1e-9;
// Path points are solved in double at ~0.03 m from the origin.
constexpr double kPointTol = 1e-12;

TEST(LensOpticsTest, FresnelTextbookValues) {
  // Normal incidence, air -> water: ((n - 1) / (n + 1))^2 = 0.02037 (Hecht, Optics, eq. 4.47).
  const double n = kWaterRefractiveIndex;
  EXPECT_NEAR(fresnel_dielectric(1.0, 1.0, n), std::pow((n - 1) / (n + 1), 2), 1e-15);
  EXPECT_NEAR(fresnel_dielectric(1.0, 1.0, n), 0.020373, 1e-6);
  // Glass n = 1.5: 4 % at normal incidence; at Brewster's angle (56.31 deg) only s is reflected:
  // R = rs^2 / 2 with rs = cos(2 thB)... = -(n^2 - 1) / (n^2 + 1) -> R = 0.0739 (Hecht fig. 4.49).
  EXPECT_NEAR(fresnel_dielectric(1.0, 1.0, 1.5), 0.04, 1e-12);
  const double brewster = std::atan(1.5);
  EXPECT_NEAR(fresnel_dielectric(std::cos(brewster), 1.0, 1.5), 0.5 * std::pow((1.5 * 1.5 - 1) / (1.5 * 1.5 + 1), 2),
              1e-12);
  // Grazing incidence reflects everything; total internal reflection beyond the critical angle
  // asin(1 / 1.333) = 48.61 deg.
  EXPECT_NEAR(fresnel_dielectric(0.0, 1.0, n), 1.0, 1e-12);
  const double critical = std::asin(1 / n);
  EXPECT_NEAR(critical / kDeg, 48.61, 0.01);
  EXPECT_LT(fresnel_dielectric(std::cos(critical - 1e-3), n, 1.0), 1.0);
  EXPECT_EQ(fresnel_dielectric(std::cos(critical + 1e-3), n, 1.0), 1.0);
  // Reciprocity (Stokes): the same interface crossed backwards reflects the same fraction.
  for (double th = 0; th < 89; th += 7) {
    const double sin_t = std::sin(th * kDeg) / n;
    EXPECT_NEAR(fresnel_dielectric(std::cos(th * kDeg), 1.0, n),
                fresnel_dielectric(std::sqrt(1 - sin_t * sin_t), n, 1.0), 1e-12)
        << th;
  }
}

TEST(LensOpticsTest, RefractObeysSnellAndReportsTir) {
  Rng rng(3, 0, 0);
  for (int i = 0; i < 1000; ++i) {
    Vec3 n = Vec3(rng.normal(), rng.normal(), rng.normal()).normalized();
    Vec3 d = Vec3(rng.normal(), rng.normal(), rng.normal()).normalized();
    if (d.dot(n) > 0) d = -d;
    for (auto [ei, et] : {std::pair{1.0, 1.333}, std::pair{1.333, 1.0}}) {
      auto t = refract(d, n, ei, et);
      const double sin_i = d.cross(n).norm();
      if (ei * sin_i > et) {
        EXPECT_FALSE(t.has_value());
        continue;
      }
      ASSERT_TRUE(t.has_value());
      EXPECT_NEAR(t->norm(), 1, kDirTol);
      EXPECT_NEAR(ei * sin_i, et * t->cross(n).norm(), kDirTol);
      EXPECT_NEAR(t->dot(d.cross(n)), 0, kDirTol);  // in the plane of incidence
      EXPECT_LT(t->dot(n), 0);                      // continues through the boundary
    }
  }
}

class LensPathTest : public ::testing::Test {
 protected:
  EmbreeDevice device;
  TraceOptions options;
};

TEST_F(LensPathTest, ApexRayIsUndeviated) {
  for (bool camera_side : {false, true}) {
    for (double theta : {20.0, 70.0, 90.0, 150.0}) {
      GlassPlane plane = test_plane(0.03, camera_side);
      DropScene scene(device, plane, {test_drop(0, plane, 0, 0, 1e-3, theta)}, CapGeometry::kAnalytic, 48);
      std::vector<PathEvent> events;
      PathResult r = trace_path(scene, Vec3::Zero(), Vec3::UnitZ(), options, &events);
      ASSERT_TRUE(r.touched_water);
      EXPECT_EQ(events.size(), 2u);
      EXPECT_NEAR((r.exit_direction - Vec3::UnitZ()).norm(), 0, kDirTol) << theta << " " << camera_side;
      // Normal incidence twice: (1 - R0)^2 of the light goes on, the rest is reflected.
      const double r0 = fresnel_dielectric(1, 1, kWaterRefractiveIndex);
      EXPECT_NEAR(r.scene_weight, (1 - r0) * (1 - r0), 1e-12);
      // The first surface's reflection goes straight back to the camera; the second's, inside the
      // water, is not followed (environment).
      EXPECT_NEAR(r.camera_weight, r0, 1e-12);
      EXPECT_NEAR(r.environment_weight, (1 - r0) * r0, 1e-12);
    }
  }
  // An oblique ray whose in-water segment ends at the apex: there the cap is parallel to the glass,
  // so the drop acts as a flat slab and the exit direction equals the incoming one.
  GlassPlane plane = test_plane();
  const PlacedDrop drop = test_drop(0, plane, 0.004, -0.002, 1.5e-3, 80);
  DropScene scene(device, plane, {drop}, CapGeometry::kAnalytic, 48);
  const Vec3 apex = drop.sphere_center + drop.sphere_radius * plane.water_normal;
  const double height = plane.height(apex);
  for (double tilt_deg : {5.0, 20.0, 35.0}) {
    const Vec3 d_water = Vec3(std::sin(tilt_deg * kDeg), 0.3 * std::sin(tilt_deg * kDeg), 1).normalized();
    const Vec3 entry = apex - d_water * (height / d_water.dot(plane.water_normal));
    // The air ray that refracts into d_water: reverse it out through the base.
    const Vec3 d_air = -*refract(-d_water, plane.water_normal, kWaterRefractiveIndex, 1.0);
    const Vec3 origin = entry - 0.02 * d_air;
    std::vector<PathEvent> events;
    PathResult r = trace_path(scene, origin, d_air, options, &events);
    ASSERT_EQ(events.size(), 2u);
    EXPECT_NEAR((events[1].point - apex).norm(), 0, kPointTol);
    EXPECT_NEAR((r.exit_direction - d_air).norm(), 0, kDirTol) << tilt_deg;
  }
}

// Pixel coordinates where an exit direction lands in the view of a camera with focal f, center 0.
Eigen::Vector2d landing(const Vec3& d, double f) { return {f * d.x() / d.z(), f * d.y() / d.z()}; }

TEST_F(LensPathTest, FlatDropMapsTheImageOntoItself) {
  // Contact angle 0.05 deg: a 2 mm drop is 0.9 um high. Every ray must land within 0.05 px of where
  // it would without the drop (focal length 500 px); the sphere radius is 2.3 m, which exercises the
  // double-precision re-solve of the float Embree crossings.
  constexpr double kFocalPx = 500, kMaxShiftPx = 0.05;
  for (bool camera_side : {false, true}) {
    GlassPlane plane = test_plane(0.03, camera_side);
    DropScene scene(device, plane, {test_drop(0, plane, 0.001, 0.0005, 2e-3, 0.05)}, CapGeometry::kAnalytic, 48);
    int touched = 0;
    for (int i = -20; i <= 20; ++i) {
      for (int j = -20; j <= 20; ++j) {
        const Vec3 d = Vec3(0.001 / 0.03 + i * 1e-4 * 100 / 30, 0.0005 / 0.03 + j * 1e-4 * 100 / 30, 1).normalized();
        PathResult r = trace_path(scene, Vec3::Zero(), d, options);
        if (!r.touched_water) continue;
        ++touched;
        EXPECT_LT((landing(r.exit_direction, kFocalPx) - landing(d, kFocalPx)).norm(), kMaxShiftPx);
        EXPECT_NEAR(r.scene_weight + r.environment_weight + r.camera_weight, 1, 1e-12);
      }
    }
    EXPECT_GT(touched, 1000) << "rays inside the 2 mm footprint";
  }
}

TEST_F(LensPathTest, SymmetricDropInvertsTheViewAboutItsCenter) {
  // A hemispherical drop (radius 1 mm) centered on the optical axis is a strong positive lens
  // (f = R / (n - 1) = 3 mm): rays through points left of its center leave towards the right, and a
  // pair of rays mirrored about the center leave mirrored.
  constexpr double kFocalPx = 500;
  for (bool camera_side : {false, true}) {
    GlassPlane plane = test_plane(0.03, camera_side);
    DropScene scene(device, plane, {test_drop(0, plane, 0, 0, 1e-3, 90)}, CapGeometry::kAnalytic, 48);
    int checked = 0;
    for (int i = -6; i <= 6; ++i) {
      for (int j = -6; j <= 6; ++j) {
        if (i == 0 && j == 0) continue;
        const Eigen::Vector2d offset(i * 0.12e-3, j * 0.12e-3);  // on the glass, within 0.85 R
        if (offset.norm() > 0.85e-3) continue;
        const Vec3 d = Vec3(offset.x() / 0.03, offset.y() / 0.03, 1).normalized();
        const Vec3 d_mirror = Vec3(-offset.x() / 0.03, -offset.y() / 0.03, 1).normalized();
        PathResult r = trace_path(scene, Vec3::Zero(), d, options);
        PathResult m = trace_path(scene, Vec3::Zero(), d_mirror, options);
        ASSERT_TRUE(r.touched_water && m.touched_water);
        if (r.scene_weight == 0) continue;  // cut after total internal reflections
        const Eigen::Vector2d in = landing(d, kFocalPx), out = landing(r.exit_direction, kFocalPx);
        EXPECT_LT(out.dot(in), 0) << "not inverted at offset " << offset.transpose();
        EXPECT_GT(out.norm(), in.norm()) << "the view through a drop is minified, so it spans more";
        EXPECT_NEAR((out + landing(m.exit_direction, kFocalPx)).norm(), 0, 1e-6);
        ++checked;
      }
    }
    EXPECT_GT(checked, 100);
  }
}

// Random drop fields with every kind of trouble: overlapping drops, contact angles from nearly flat
// to nearly spherical, rays from the whole field of view.
std::vector<PlacedDrop> random_drops(const GlassPlane& plane, int n, uint64_t seed) {
  std::vector<PlacedDrop> drops;
  Rng rng(seed, 1, 0);
  for (int i = 0; i < n; ++i) {
    const double theta = i % 5 == 0 ? 0.01 : (i % 5 == 1 ? 179.99 : 5 + 170 * rng.uniform_double());
    drops.push_back(test_drop(i, plane, rng.uniform(-0.01f, 0.01f), rng.uniform(-0.008f, 0.008f),
                              0.3e-3 + 2.5e-3 * rng.uniform_double(), theta));
  }
  return drops;
}

TEST_F(LensPathTest, SnellAndEnergyHoldAtSampledHits) {
  int refractions = 0, tirs = 0, through_base = 0, glass_tirs = 0;
  for (double glass_mm : {0.0, 1.0})
  for (bool camera_side : {false, true}) {
    for (CapGeometry geometry : {CapGeometry::kAnalytic, CapGeometry::kTriangles}) {
      options.glass_thickness_m = 1e-3 * glass_mm;
      GlassPlane plane = test_plane(0.03, camera_side);
      DropScene scene(device, plane, random_drops(plane, 40, camera_side ? 2 : 1), geometry, 32);
      Rng rng(5, 0, 0);
      for (int i = 0; i < 4000; ++i) {
        const Vec3 d = Vec3(rng.uniform(-0.35f, 0.35f), rng.uniform(-0.27f, 0.27f), 1).normalized();
        std::vector<PathEvent> events;
        PathResult r = trace_path(scene, Vec3::Zero(), d, options, &events);
        ASSERT_TRUE(r.exit_direction.allFinite());
        EXPECT_GE(r.scene_weight, 0);
        EXPECT_LE(r.scene_weight, 1);
        EXPECT_GE(r.environment_weight, 0);
        EXPECT_LE(r.environment_weight, 1);
        EXPECT_GE(r.camera_weight, 0);
        EXPECT_LE(r.camera_weight, 1);
        if (r.touched_water) {
          EXPECT_NEAR(r.scene_weight + r.environment_weight + r.camera_weight, 1, 1e-12);
        } else {
          EXPECT_EQ(r.scene_weight, 1);
        }
        for (const PathEvent& e : events) {
          ASSERT_TRUE(e.point.allFinite() && e.d_out.allFinite());
          EXPECT_NEAR(e.normal.norm(), 1, kDirTol);
          EXPECT_LE(e.d_in.dot(e.normal), 1e-12) << "normal faces the incoming ray";
          EXPECT_GE(e.reflectance, 0);
          EXPECT_LE(e.reflectance, 1);
          const double sin_i = e.d_in.cross(e.normal).norm();
          if (e.total_internal_reflection) {
            ++tirs;
            glass_tirs += e.glass_face;
            EXPECT_GT(e.eta_i * sin_i, e.eta_t * (1 - 1e-12));
            EXPECT_NEAR((e.d_out - reflect(e.d_in, e.normal)).norm(), 0, kDirTol);
          } else {
            ++refractions;
            through_base += e.through_base;
            EXPECT_NEAR(e.eta_i * sin_i, e.eta_t * e.d_out.cross(e.normal).norm(), kDirTol);
            EXPECT_NEAR(e.d_out.dot(e.d_in.cross(e.normal)), 0, kDirTol);
            EXPECT_LE(e.d_out.dot(e.normal), 0);
          }
          if (e.glass_face) {  // the slab's inner face (-h) or its outer face between drops (0)
            const double h = plane.height(e.point);
            EXPECT_TRUE(std::abs(h) < kPointTol || std::abs(h + options.glass_thickness_m) < kPointTol) << h;
            continue;
          }
          if (geometry == CapGeometry::kAnalytic && !e.through_base) {
            // The crossing lies on its drop's sphere, on the water side of the glass.
            const PlacedDrop& p = scene.drops()[e.drop];
            EXPECT_NEAR((e.point - p.sphere_center).norm(), p.sphere_radius, 1e-12 + 1e-12 * p.sphere_radius);
            EXPECT_GE(plane.height(e.point), -1e-12);
          }
          if (e.through_base) {
            EXPECT_NEAR(plane.height(e.point), 0, kPointTol);
          }
        }
      }
    }
  }
  EXPECT_GT(refractions, 5000);
  EXPECT_GT(tirs, 20) << "the field must exercise total internal reflection";
  EXPECT_GT(glass_tirs, 5) << "and light trapped in the slab";
  EXPECT_GT(through_base, 1000);
}

TEST_F(LensPathTest, GlassSlabShiftsRaysAndLeavesCleanGlassUnchanged) {
  // One drop on the scene side of a glass at 3 cm. Through a 1 mm slab (n = 1.52) a camera ray at
  // angle a refracts to asin(sin a / 1.52) and meets the drop's base h (tan a - tan a_g) nearer the
  // axis than the thin glass's straight ray; a ray that misses the drops leaves in its own direction.
  constexpr double kH = 1e-3;
  GlassPlane plane = test_plane(0.03, false);
  const PlacedDrop drop = test_drop(0, plane, 0.009, 0, 2e-3, 60);
  DropScene scene(device, plane, {drop}, CapGeometry::kAnalytic, 48);
  TraceOptions thin = options, slab = options;
  slab.glass_thickness_m = kH;
  for (double x_base : {0.0085, 0.0095}) {
    const Vec3 d = Vec3(x_base, 0, 0.03).normalized();
    std::vector<PathEvent> ev_thin, ev_slab;
    trace_path(scene, Vec3::Zero(), d, thin, &ev_thin);
    const PathResult r = trace_path(scene, Vec3::Zero(), d, slab, &ev_slab);
    ASSERT_TRUE(r.touched_water);
    ASSERT_GE(ev_slab.size(), 2u);
    EXPECT_TRUE(ev_slab[0].glass_face);    // air -> glass at the inner face
    EXPECT_TRUE(ev_slab[1].through_base);  // glass -> water under the drop
    const double sin_a = d.x(), tan_a = d.x() / d.z();
    const double sin_g = sin_a / kCrownGlassRefractiveIndex, tan_g = sin_g / std::sqrt(1 - sin_g * sin_g);
    EXPECT_NEAR(ev_thin[0].point.x() - ev_slab[1].point.x(), kH * (tan_a - tan_g), 1e-12);
    // Both enter the water at the same angle (n sin is conserved across parallel faces).
    EXPECT_NEAR((ev_slab[1].d_out - ev_thin[0].d_out).norm(), 0, kDirTol);
  }
  const Vec3 d_clear = Vec3(-0.2, 0.1, 1).normalized();
  const PathResult r = trace_path(scene, Vec3::Zero(), d_clear, slab);
  EXPECT_FALSE(r.touched_water);
  EXPECT_EQ(r.scene_weight, 1);
  EXPECT_NEAR((r.exit_direction - d_clear).norm(), 0, kDirTol);
}

TEST_F(LensPathTest, GrazingRimRaysStayFinite) {
  // Rays aimed at the contact line from just inside and just outside, for extreme contact angles.
  for (double theta : {0.001, 1.0, 45.0, 90.0, 135.0, 179.0, 179.999}) {
    for (bool camera_side : {false, true}) {
      GlassPlane plane = test_plane(0.03, camera_side);
      const PlacedDrop drop = test_drop(0, plane, 0.002, 0.001, 1e-3, theta);
      DropScene scene(device, plane, {drop}, CapGeometry::kAnalytic, 48);
      for (double rel : {1 - 1e-9, 1 - 1e-6, 1.0, 1 + 1e-6}) {
        for (int k = 0; k < 16; ++k) {
          const double a = 2 * M_PI * k / 16;
          const Vec3 target = drop.base_center + rel * drop.base_radius * Vec3(std::cos(a), std::sin(a), 0);
          std::vector<PathEvent> events;
          PathResult r = trace_path(scene, Vec3::Zero(), target.normalized(), options, &events);
          ASSERT_TRUE(r.exit_direction.allFinite()) << theta;
          ASSERT_TRUE(std::isfinite(r.scene_weight) && std::isfinite(r.environment_weight));
          if (r.touched_water) {
            EXPECT_NEAR(r.scene_weight + r.environment_weight + r.camera_weight, 1, 1e-12);
          }
          EXPECT_LE(int(events.size()), 4 * options.max_bounces + 64);
        }
      }
    }
  }
}

TEST_F(LensPathTest, TotalInternalReflectionIsBounded) {
  // Light entering a steep drop (contact angle 120 deg) through its base meets the overhanging cap
  // beyond the critical angle: paths must end after max_bounces.
  GlassPlane plane = test_plane();
  DropScene scene(device, plane, {test_drop(0, plane, 0, 0, 2e-3, 120)}, CapGeometry::kAnalytic, 48);
  for (int bounces : {0, 1, 4}) {
    TraceOptions o;
    o.max_bounces = bounces;
    int saw_tir = 0;
    for (int i = 0; i < 400; ++i) {
      const Vec3 d = Vec3(-0.058 + 0.116 * i / 400.0, 0.0013, 1).normalized();
      std::vector<PathEvent> events;
      PathResult r = trace_path(scene, Vec3::Zero(), d, o, &events);
      int tir = 0;
      for (const PathEvent& e : events) tir += e.total_internal_reflection;
      EXPECT_LE(tir, bounces + 1);
      saw_tir += tir > 0;
      if (tir > bounces) {
        EXPECT_EQ(r.scene_weight, 0);
      }
      if (r.touched_water && r.scene_weight == 0 && tir <= bounces) {
        // Not cut, yet nothing reaches the scene: the path left backwards, towards the camera.
        EXPECT_GT(r.camera_weight, 0.5);
      }
    }
    EXPECT_GT(saw_tir, 0);
  }
}

TEST_F(LensPathTest, OverlappingDropsMergeIntoOneBody) {
  // Two hemispheres whose centers are 1.2 mm apart (radius 1 mm): a ray through the overlap enters
  // the water once and leaves once, never at a point inside the other drop.
  for (CapGeometry geometry : {CapGeometry::kAnalytic, CapGeometry::kTriangles}) {
    GlassPlane plane = test_plane();
    const PlacedDrop a = test_drop(0, plane, -0.6e-3, 0, 1e-3, 90), b = test_drop(1, plane, 0.6e-3, 0, 1e-3, 90);
    DropScene scene(device, plane, {a, b}, geometry, 64);
    int through_overlap = 0;
    for (int i = -20; i <= 20; ++i) {
      const Vec3 d = Vec3(i * 0.05e-3 / 0.03, 0.1e-3 / 0.03, 1).normalized();
      std::vector<PathEvent> events;
      PathResult r = trace_path(scene, Vec3::Zero(), d, options, &events);
      ASSERT_TRUE(r.touched_water);
      int refractions = 0;
      for (const PathEvent& e : events) {
        refractions += !e.total_internal_reflection;
        if (!e.through_base) {
          const PlacedDrop& other = scene.drops()[1 - e.drop];
          // Facets of 64-segment caps lie up to R (1 - cos(2 pi / 64)) inside the sphere.
          const double inside = geometry == CapGeometry::kAnalytic ? 1 - 1e-9 : std::cos(2 * M_PI / 64);
          EXPECT_GE((e.point - other.sphere_center).norm(), other.sphere_radius * inside);
        }
      }
      const int tir = int(events.size()) - refractions;
      if (tir > options.max_bounces) continue;  // trapped by total internal reflection, cut
      EXPECT_EQ(refractions, 2) << "enter once, leave once; ray " << i << " geometry " << int(geometry)
                                << " tir " << tir;
      through_overlap += std::abs(i * 0.05e-3) < 0.4e-3;
    }
    EXPECT_GT(through_overlap, 10);
  }
}

TEST(LensEmbreeTest, DeviceErrorsBecomeExceptions) {
  EmbreeDevice device;
  // An invalid geometry type makes Embree report RTC_ERROR_INVALID_ARGUMENT through the callback.
  RTCGeometry g = rtcNewGeometry(device.handle(), RTCGeometryType(12345));
  EXPECT_EQ(g, nullptr);
  EXPECT_THROW(device.throw_if_error("a bad geometry"), InternalError);
  EXPECT_NO_THROW(device.throw_if_error("nothing"));  // reported once
}

}  // namespace
}  // namespace weathergs::generator::lens
