// The lens_droplets spec: defaults, strictness, validation messages, resolved JSON round trip, and
// the seeded drop sampler.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "generator/lens/drops.h"
#include "generator/lens/lens_spec.h"
#include "tests/generator_lens/lens_test_util.h"

namespace weathergs::generator::lens {
namespace {

LensDropletSpec parse(const std::string& text) {
  Json j = Json::parse(text);
  return parse_lens_droplet_spec(JsonReader(j, "spec.json", "/effects/lens_droplets"));
}

std::string error_of(const std::string& text) {
  try {
    parse(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(LensSpecTest, DatasetFormatExampleAndDefaults) {
  LensDropletSpec s = parse(R"({"count": 60, "radius_mm": [0.5, 3.0], "contact_angle_deg": 70,
                                "glass_distance_m": 0.03, "attach": "lens"})");
  EXPECT_EQ(s.count, 60);
  EXPECT_EQ(s.radius_mm[0], 0.5);
  EXPECT_EQ(s.radius_mm[1], 3.0);
  EXPECT_EQ(s.contact_angle_deg[0], 70);
  EXPECT_EQ(s.contact_angle_deg[1], 70);
  EXPECT_EQ(s.attach, Attach::kLens);
  EXPECT_EQ(s.drop_side, DropSide::kScene);
  EXPECT_EQ(s.refractive_index, 1.333);
  EXPECT_EQ(s.samples_per_pixel, 4);
  EXPECT_EQ(s.geometry, CapGeometry::kAnalytic);
  EXPECT_FALSE(s.environment_radiance.has_value());
  LensDropletSpec empty = parse("{}");
  EXPECT_EQ(empty.count, 60);
  EXPECT_EQ(empty.glass_thickness_mm, 0);  // the thin glass unless given (the physical style gives 1 mm)
  EXPECT_EQ(empty.glass_refractive_index, kCrownGlassRefractiveIndex);
}

TEST(LensSpecTest, ResolvedJsonRoundTrips) {
  LensDropletSpec s = parse(R"({"count": 7, "radius_mm": 2, "contact_angle_deg": [40, 110],
      "attach": "window", "window": {"center_world": [1, 2, 3], "normal_world": [0, 1, 0],
      "size_m": [2, 1]}, "environment_radiance": [0.1, 0.2, 0.3], "geometry": "triangles",
      "drop_side": "camera", "samples_per_pixel": 9, "slide_speed_mm_s": 3})");
  Json j = lens_droplet_spec_to_json(s);
  LensDropletSpec again = parse_lens_droplet_spec(JsonReader(j, "resolved"));
  EXPECT_EQ(lens_droplet_spec_to_json(again).dump(), j.dump());
  EXPECT_EQ(j["radius_mm"], Json::array({2.0, 2.0}));
  EXPECT_EQ(j["window"]["up_world"], Json::array({0.0, 0.0, 1.0}));
  Json d = lens_droplet_spec_to_json(parse("{}"));
  EXPECT_EQ(d["environment_radiance"], "mean");
  EXPECT_TRUE(d["window"].is_null());
  EXPECT_EQ(lens_droplet_spec_to_json(parse_lens_droplet_spec(JsonReader(d, "r"))).dump(), d.dump());
}

TEST(LensSpecTest, ErrorsNameTheKeyAndTheRule) {
  EXPECT_NE(error_of(R"({"cuont": 3})").find("cuont"), std::string::npos);
  EXPECT_NE(error_of(R"({"count": -1})").find("/effects/lens_droplets/count"), std::string::npos);
  EXPECT_NE(error_of(R"({"radius_mm": [3, 1]})").find("radius_mm"), std::string::npos);
  EXPECT_NE(error_of(R"({"radius_mm": [1, 2, 3]})").find("[min, max]"), std::string::npos);
  EXPECT_NE(error_of(R"({"contact_angle_deg": 180})").find("< 180"), std::string::npos);
  EXPECT_NE(error_of(R"({"contact_angle_deg": 0})").find("contact_angle_deg"), std::string::npos);
  EXPECT_NE(error_of(R"({"attach": "car"})").find("\"lens\", \"window\""), std::string::npos);
  EXPECT_NE(error_of(R"({"glass_thickness_mm": -1})").find("glass_thickness_mm"), std::string::npos);
  EXPECT_NE(error_of(R"({"glass_distance_m": 0.004, "glass_thickness_mm": 3})").find("half of glass_distance_m"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"glass_refractive_index": 0.9})").find("glass_refractive_index"), std::string::npos);
  EXPECT_NE(error_of(R"({"glass_distance_m": 0})").find("glass_distance_m"), std::string::npos);
  EXPECT_NE(error_of(R"({"samples_per_pixel": 0})").find("samples_per_pixel"), std::string::npos);
  EXPECT_NE(error_of(R"({"refractive_index": 0.5})").find("refractive_index"), std::string::npos);
  EXPECT_NE(error_of(R"({"environment_radiance": "max"})").find("\"mean\""), std::string::npos);
  EXPECT_NE(error_of(R"({"window": {"center_world": [0,0,0], "normal_world": [0,1,0], "size_m": [1,1]}})")
                .find("attach \"lens\""),
            std::string::npos);
  EXPECT_NE(error_of(R"({"attach": "window", "window": {"center_world": [0,0,0], "normal_world": [0,0,1],
                          "size_m": [1,1]}})")
                .find("up_world"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"attach": "window", "window": {"normal_world": [0,1,0], "size_m": [1,1]}})")
                .find("center_world"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"attach": "window", "window": {"center_world": [0,0,0], "normal_world": [0,1,0],
                          "size_m": [1,1], "tilt": 3}})")
                .find("tilt"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"count": 1.5})").find("integer"), std::string::npos);
  EXPECT_NE(error_of(R"([1])").find("object"), std::string::npos);
}

TEST(LensSpecTest, SamplerIsSeededAndFollowsTheSpec) {
  const Camera cam = testing::test_camera(600, 400, 520);
  LensDropletSpec s = parse(R"({"count": 4000, "radius_mm": [0.5, 3.0], "contact_angle_deg": [30, 120],
                                "slide_speed_mm_s": 2, "slide_min_radius_mm": 1.5})");
  DropField a = sample_drop_field(s, 7, cam), b = sample_drop_field(s, 7, cam), c = sample_drop_field(s, 8, cam);
  ASSERT_EQ(a.drops.size(), 4000u);
  int differ = 0, sliding = 0, below_geo_mean = 0;
  const double geo_mean = std::sqrt(0.5e-3 * 3e-3);
  for (size_t i = 0; i < a.drops.size(); ++i) {
    const Drop& d = a.drops[i];
    EXPECT_EQ(d.center_m, b.drops[i].center_m);
    EXPECT_EQ(d.outline_radius_m, b.drops[i].outline_radius_m);
    differ += d.center_m != c.drops[i].center_m;
    EXPECT_GE(d.outline_radius_m, 0.5e-3);
    EXPECT_LE(d.outline_radius_m, 3e-3);
    EXPECT_GE(d.contact_angle_rad, 30 * testing::kDeg - 1e-12);
    EXPECT_LE(d.contact_angle_rad, 120 * testing::kDeg + 1e-12);
    EXPECT_TRUE((d.center_m.array() >= a.region_min.array()).all() && (d.center_m.array() <= a.region_max.array()).all());
    sliding += d.slide_speed_m_s > 0;
    EXPECT_EQ(d.slide_speed_m_s > 0, d.outline_radius_m >= 1.5e-3);
    below_geo_mean += d.outline_radius_m < geo_mean;
  }
  EXPECT_EQ(differ, 4000);
  // Log-uniform: half the drops below the geometric mean of the range (binomial sd = 32).
  EXPECT_NEAR(below_geo_mean, 2000, 5 * 32);
  EXPECT_GT(sliding, 0);
  // The lens-attach region covers the view of the glass (600 px at 520 px focal length, 3 cm).
  const double half_width = 0.03 * 300 / 520;
  EXPECT_LT(a.region_min.x(), -half_width);
  EXPECT_GT(a.region_max.x(), half_width);
}

TEST(LensSpecTest, GeometryOfACap) {
  // Outline radius = base radius up to 90 deg, sphere radius beyond; R = a / sin(theta).
  GlassPlane plane = testing::test_plane();
  PlacedDrop d60 = make_placed_drop(0, plane.point, plane.water_normal, 1e-3, 60 * testing::kDeg);
  EXPECT_NEAR(d60.base_radius, 1e-3, 1e-18);
  EXPECT_NEAR(d60.sphere_radius, 1e-3 / std::sin(60 * testing::kDeg), 1e-15);
  // Apex height h = R (1 - cos theta).
  const Eigen::Vector3d apex = d60.sphere_center + d60.sphere_radius * plane.water_normal;
  EXPECT_NEAR(plane.height(apex), d60.sphere_radius * (1 - std::cos(60 * testing::kDeg)), 1e-15);
  PlacedDrop d120 = make_placed_drop(0, plane.point, plane.water_normal, 1e-3, 120 * testing::kDeg);
  EXPECT_NEAR(d120.sphere_radius, 1e-3, 1e-18);
  EXPECT_NEAR(d120.base_radius, 1e-3 * std::sin(120 * testing::kDeg), 1e-15);
  EXPECT_GT(plane.height(d120.sphere_center), 0);
  // Contact angles are clamped away from 0 and 180 degrees: finite spheres.
  PlacedDrop flat = make_placed_drop(0, plane.point, plane.water_normal, 1e-3, 1e-9);
  EXPECT_TRUE(std::isfinite(flat.sphere_radius));
  EXPECT_NEAR(flat.contact_angle_rad, kMinContactAngleRad, 1e-15);
}

}  // namespace
}  // namespace weathergs::generator::lens
