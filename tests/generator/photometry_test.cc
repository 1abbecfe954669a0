// Particle photometry (generator/photometry.h): Fresnel, the water sphere's rings, the Lambert sphere's
// phase law, the environment around a view and the radiance grid, each against its closed form.
#include <gtest/gtest.h>

#include <cmath>

#include "core/constants.h"
#include "core/parallel.h"
#include "generator/photometry.h"
#include "generator/weather_spec.h"

namespace weathergs::generator {
namespace {

constexpr double kDeg = kPi / 180;

// A camera at the origin looking along world +y (horizontal), z up: OpenCV axes x right, y down.
Camera level_camera(int w = 64, int h = 48) {
  Camera c;
  c.name = "000";
  c.width = w, c.height = h;
  c.fx = c.fy = 40;
  c.cx = w / 2.0, c.cy = h / 2.0;
  c.camera_from_world.setIdentity();
  c.camera_from_world.topLeftCorner<3, 3>() << 1, 0, 0, 0, 0, -1, 0, 1, 0;  // rows: x_c, y_c, z_c in world
  c.exposure_s = 1.0 / 60;
  return c;
}

Image constant_image(int w, int h, float v) { return Image(w, h, 3, ColorSpace::kLinear, v); }

TEST(Photometry, FresnelMatchesClosedForms) {
  const double n = kWaterRefractiveIndex;
  // Normal incidence: ((n - 1) / (n + 1))^2 (Hecht, Optics, eq. 4.47).
  EXPECT_NEAR(fresnel_reflectance(1.0, n), std::pow((n - 1) / (n + 1), 2), 1e-12);
  EXPECT_NEAR(fresnel_reflectance(0.0, n), 1.0, 1e-12);  // grazing
  // Brewster's angle tan(i) = n: the p-polarized part vanishes, R = rs^2 / 2.
  const double ib = std::atan(n), it = std::asin(std::sin(ib) / n);
  const double rs = std::sin(ib - it) / std::sin(ib + it);  // Fresnel's sine law
  EXPECT_NEAR(fresnel_reflectance(std::cos(ib), n), 0.5 * rs * rs, 1e-12);
  // Inside the drop beyond the critical angle: total internal reflection.
  EXPECT_EQ(fresnel_reflectance(std::cos(60 * kDeg), 1 / n), 1.0);
  for (double c = 0; c <= 1; c += 0.01) {
    const double r = fresnel_reflectance(c, n);
    EXPECT_TRUE(r >= 0 && r <= 1) << c;
  }
}

TEST(Photometry, WaterSphereRingsCarryTheLightOfThreePaths) {
  const std::vector<ScatterRing> rings = water_sphere_rings(4000);
  double total = 0;
  for (const ScatterRing& r : rings) {
    total += r.weight;
    EXPECT_GE(r.theta, 0);
    EXPECT_LE(r.theta, kPi);
  }
  // The twice-refracted ray turns by 2 (i - r), at most 2 (90 - asin(1 / n)) = 82.8 degrees at
  // grazing incidence (Garg & Nayar's ~165 degree field of view of a drop).
  const double bound = 2 * (90 * kDeg - std::asin(1 / kWaterRefractiveIndex));
  EXPECT_NEAR(bound / kDeg, 82.8, 0.05);
  // One impact parameter, b^2 = 1/2 (i = 45 degrees): the three paths at their closed-form angles.
  const double i = 45 * kDeg, r = std::asin(std::sin(i) / kWaterRefractiveIndex);
  const std::vector<ScatterRing> one = water_sphere_rings(1);
  ASSERT_EQ(one.size(), 3u);
  EXPECT_NEAR(one[0].theta, 2 * (i - r), 1e-12);           // refracted
  EXPECT_NEAR(one[1].theta, kPi - 2 * i, 1e-12);           // reflected
  EXPECT_NEAR(one[2].theta, kPi + 2 * i - 4 * r, 1e-12);  // one internal reflection (< 180 here)
  // Reflection + refraction + one internal reflection: all but the light of two or more internal
  // reflections, R^2 (1 - R)^2 summed over the disk (well under 1%).
  EXPECT_GT(total, 0.99);
  EXPECT_LT(total, 1.0);
  // The kernel per steradian integrates to the same energy.
  double integral = 0;
  for (int i = 0; i < 180; ++i)
    integral += water_sphere_density_per_sr((i + 0.5) * kDeg) * 2 * kPi * (std::cos(i * kDeg) - std::cos((i + 1) * kDeg));
  EXPECT_NEAR(integral, total, 1e-3);
}

TEST(Photometry, LambertSpherePhaseLaw) {
  // Full phase: a white disk-averaged Lambert sphere has radiance (2/3) E / pi.
  EXPECT_NEAR(lambert_sphere_phase(0), 2.0 / (3 * kPi), 1e-12);
  EXPECT_NEAR(lambert_sphere_phase(kPi), 0, 1e-12);  // new phase: the lit side faces away
  // Under uniform light from every direction the sphere has the radiance of that light (x albedo).
  double integral = 0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const double a = (i + 0.5) * kPi / n;
    integral += lambert_sphere_phase(a) * 2 * kPi * std::sin(a) * kPi / n;
  }
  EXPECT_NEAR(integral, 1.0, 1e-6);
  // Monotone decreasing with the phase angle.
  for (double a = 0; a + 0.01 <= kPi; a += 0.01) EXPECT_GE(lambert_sphere_phase(a), lambert_sphere_phase(a + 0.01));
}

TEST(Photometry, EnvironmentIsTheImageInsideAndSkyOrGroundOutside) {
  const Camera cam = level_camera();
  Image img = constant_image(cam.width, cam.height, 0.2f);
  for (int y = 0; y < cam.height / 2; ++y)  // upper half (above the horizon) bright
    for (int x = 0; x < cam.width; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = 0.8f;
  const ViewEnvironment env(cam, img, Eigen::Vector3f(1.0f, 0.9f, 0.8f));
  EXPECT_NEAR(env.ground()[0], 0.2, 1e-6);  // the mean of the pixels looking below the horizon
  EXPECT_NEAR(env.radiance(Eigen::Vector3d(0, 1, 0.3).normalized())[0], 0.8, 1e-5);   // in the image, above
  EXPECT_NEAR(env.radiance(Eigen::Vector3d(0, 1, -0.3).normalized())[0], 0.2, 1e-5);  // in the image, below
  EXPECT_NEAR(env.radiance(Eigen::Vector3d(0, 0, 1))[1], 0.9, 1e-6);                    // zenith: sky
  EXPECT_NEAR(env.radiance(Eigen::Vector3d(0, -1, -0.1).normalized())[0], 0.2, 1e-6);  // behind, down: ground
}

TEST(Photometry, UniformLightGivesTheKernelsEnergy) {
  const Camera cam = level_camera();
  const ViewEnvironment env(cam, constant_image(cam.width, cam.height, 0.5f), Eigen::Vector3f::Constant(0.5f));
  double water_total = 0;
  for (const ScatterRing& r : water_sphere_rings(48)) water_total += r.weight;
  const ParticleRadianceGrid water(env, cam, ParticleOptics::kWaterSphere, 0);
  const ParticleRadianceGrid snow(env, cam, ParticleOptics::kLambertSphere, 0.9);
  for (double x : {0.0, 10.5, 32.0, 63.9})
    for (double y : {0.0, 24.0, 47.9}) {
      EXPECT_NEAR(water.at(x, y)[0], 0.5 * water_total, 1e-5) << x << "," << y;
      EXPECT_NEAR(snow.at(x, y)[2], 0.45, 1e-5) << x << "," << y;  // albedo x radiance, normalized exactly
    }
}

TEST(Photometry, DropsInFrontOfTheSkyShowTheGround) {
  // Garg & Nayar: a drop images a wide cone of its surroundings. Seen against a bright sky it is
  // darker than the sky (it shows the ground too), against the dark ground brighter than the ground.
  const Camera cam = level_camera();
  Image img = constant_image(cam.width, cam.height, 0.1f);
  for (int y = 0; y < cam.height / 2; ++y)
    for (int x = 0; x < cam.width; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = 1.0f;
  const ViewEnvironment env(cam, img, Eigen::Vector3f::Constant(1.0f));
  const ParticleRadianceGrid water(env, cam, ParticleOptics::kWaterSphere, 0);
  const float top = water.at(32, 2)[0], bottom = water.at(32, 46)[0];
  EXPECT_LT(top, 0.9f);
  EXPECT_GT(bottom, 0.2f);
  EXPECT_GT(top, bottom);  // still mostly what lies behind it
}

TEST(Photometry, SunLightsASnowFlakeByThePhaseLaw) {
  const Camera cam = level_camera();
  const ViewEnvironment dark(cam, constant_image(cam.width, cam.height, 0.0f), Eigen::Vector3f::Zero());
  SunLight sun;
  sun.irradiance = Eigen::Vector3f::Constant(2.0f);
  const Eigen::Vector3d d = cam.ray_direction_world({32, 32});  // a grid node (every 16 px): no interpolation
  for (double phase_deg : {0.0, 60.0, 120.0}) {
    // Sun at `phase_deg` from the direction towards the camera (-d), in the plane of d and world z.
    const double a = phase_deg * kDeg;
    const Eigen::Vector3d up = (Eigen::Vector3d::UnitZ() - d.z() * d).normalized();
    sun.to_sun_world = std::cos(a) * -d + std::sin(a) * up;
    const ParticleRadianceGrid flake(dark, cam, ParticleOptics::kLambertSphere, 0.9, &sun);
    EXPECT_NEAR(flake.at(32, 32)[0], 0.9 * 2.0 * lambert_sphere_phase(a), 1e-5) << phase_deg;
    const ParticleRadianceGrid drop(dark, cam, ParticleOptics::kWaterSphere, 0, &sun);
    EXPECT_NEAR(drop.at(32, 32)[0], 2.0 * water_sphere_density_per_sr(kPi - a), 1e-5) << phase_deg;
  }
}

TEST(Photometry, GridIsTheSameOnOneAndTwoThreads) {
  const Camera cam = level_camera(200, 120);
  Image img(cam.width, cam.height, 3, ColorSpace::kLinear);
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = float(0.5 + 0.5 * std::sin(0.1 * x + 0.07 * y + c));
  const ViewEnvironment env(cam, img, Eigen::Vector3f(1, 1, 1));
  std::vector<float> runs[2];
  for (int t : {1, 2}) {
    set_num_threads(t);
    const ParticleRadianceGrid g(env, cam, ParticleOptics::kWaterSphere, 0);
    for (int y = 0; y < cam.height; y += 7)
      for (int x = 0; x < cam.width; x += 7)
        for (int c = 0; c < 3; ++c) runs[t - 1].push_back(g.at(x, y)[c]);
  }
  set_num_threads(0);
  EXPECT_EQ(runs[0], runs[1]);
}

TEST(Photometry, SpecShadingAndSun) {
  auto parse = [](const Json& j) { return parse_weather_spec(JsonReader(j, "spec.json")); };
  const Json rain = {{"rain", {{"rate_mm_h", 25}}}};
  // Physical style: the optics; paper style: the weights.
  EXPECT_EQ(parse({{"effects", rain}}).rain->appearance.shading, ParticleShading::kOptics);
  EXPECT_EQ(parse({{"style", "paper"}, {"effects", rain}}).rain->appearance.shading, ParticleShading::kWeighted);
  // Weights without a shading name: the weighted model (resolved specs from before "shading").
  const Json old = {{"rain", {{"rate_mm_h", 25}, {"appearance", {{"environment_weight", 0.5}, {"sky_weight", 0.4}}}}}};
  EXPECT_EQ(parse({{"effects", old}}).rain->appearance.shading, ParticleShading::kWeighted);
  // Contradictions are errors naming the key.
  const Json bad_weights = {{"rain", {{"rate_mm_h", 25}, {"appearance", {{"shading", "optics"}, {"sky_weight", 0.4}}}}}};
  EXPECT_THROW(parse({{"effects", bad_weights}}), InputError);
  const Json rain_albedo = {{"rain", {{"rate_mm_h", 25}, {"appearance", {{"albedo", 0.5}}}}}};
  EXPECT_THROW(parse({{"effects", rain_albedo}}), InputError);
  const Json snow = {{"snow", {{"rate_mm_h", 2}, {"appearance", {{"albedo", 0.8}}}}}};
  EXPECT_DOUBLE_EQ(parse({{"effects", snow}}).snow->appearance.albedo, 0.8);
  const Json snow_bad = {{"snow", {{"rate_mm_h", 2}, {"appearance", {{"albedo", 1.5}}}}}};
  EXPECT_THROW(parse({{"effects", snow_bad}}), InputError);
  // The sun: all three keys, Blender's angles, and the resolved spec reads back the same.
  const Json sun = {{"sun", {{"elevation_deg", 30}, {"azimuth_deg", 90}, {"irradiance", {1, 2, 3}}}}};
  const WeatherSpec s = parse({{"effects", snow}, {"lighting", sun}});
  ASSERT_TRUE(s.sun);
  EXPECT_NEAR(s.sun->to_sun_world.x(), std::cos(30 * kDeg), 1e-12);  // azimuth 90: towards +x
  EXPECT_NEAR(s.sun->to_sun_world.z(), 0.5, 1e-12);
  const WeatherSpec back = parse(s.to_json());
  ASSERT_TRUE(back.sun);
  EXPECT_NEAR((back.sun->to_sun_world - s.sun->to_sun_world).norm(), 0, 1e-12);
  EXPECT_EQ(back.sun->irradiance, s.sun->irradiance);
  EXPECT_EQ(back.snow->appearance.albedo, 0.8);
  const Json no_irradiance = {{"sun", {{"elevation_deg", 30}, {"azimuth_deg", 90}}}};
  EXPECT_THROW(parse({{"effects", snow}, {"lighting", no_irradiance}}), InputError);
  const Json extra = {{"sun", {{"elevation_deg", 30}, {"azimuth_deg", 90}, {"irradiance", {1, 2, 3}}, {"x", 1}}}};
  EXPECT_THROW(parse({{"effects", snow}, {"lighting", extra}}), InputError);
}

TEST(Photometry, LensDropEnvironmentDefaultsByStyle) {
  auto parse = [](const Json& j) { return parse_weather_spec(JsonReader(j, "spec.json")); };
  const Json lens = {{"lens_droplets", {{"count", 5}}}};
  // Physical: the sky lights the drops' unfollowed paths (agrees with Cycles); paper: the view's mean.
  EXPECT_TRUE(parse({{"effects", lens}}).lens_droplets->environment_sky);
  EXPECT_FALSE(parse({{"style", "paper"}, {"effects", lens}}).lens_droplets->environment_sky);
  const Json mean = {{"lens_droplets", {{"count", 5}, {"environment_radiance", "mean"}}}};
  EXPECT_FALSE(parse({{"effects", mean}}).lens_droplets->environment_sky);
  const Json sky = {{"lens_droplets", {{"count", 5}, {"environment_radiance", "sky"}}}};
  const WeatherSpec s = parse({{"style", "paper"}, {"effects", sky}});
  EXPECT_TRUE(s.lens_droplets->environment_sky);
  EXPECT_EQ(s.to_json()["effects"]["lens_droplets"]["environment_radiance"], "sky");  // resolved spec says so
  const Json bad = {{"lens_droplets", {{"count", 5}, {"environment_radiance", "sun"}}}};
  EXPECT_THROW(parse({{"effects", bad}}), InputError);
}

TEST(Photometry, PhysicalSnowDrawsItsFaintFlakes) {
  auto parse = [](const Json& j) { return parse_weather_spec(JsonReader(j, "spec.json")); };
  const Json snow = {{"snow", {{"rate_mm_h", 2.5}}}}, rain = {{"rain", {{"rate_mm_h", 25}}}};
  // Physical snow: the cutoff its whole population agrees with Cycles at; rain and the paper style
  // keep the render block's.
  const WeatherSpec s = parse({{"effects", snow}});
  ASSERT_TRUE(s.snow->visibility_cutoff.has_value());
  EXPECT_EQ(*s.snow->visibility_cutoff, kPhysicalSnowVisibilityCutoff);
  EXPECT_EQ(s.snow->render_for(s.render).visibility_cutoff, kPhysicalSnowVisibilityCutoff);
  EXPECT_EQ(s.render.visibility_cutoff, RenderOptions{}.visibility_cutoff);
  EXPECT_FALSE(parse({{"effects", rain}}).rain->visibility_cutoff.has_value());
  EXPECT_FALSE(parse({{"style", "paper"}, {"effects", snow}}).snow->visibility_cutoff.has_value());
  // A cutoff the spec gives wins: the render block's for every species, the effect's for its own.
  const WeatherSpec given = parse({{"effects", snow}, {"render", {{"visibility_cutoff", 0.005}}}});
  EXPECT_FALSE(given.snow->visibility_cutoff.has_value());
  EXPECT_EQ(given.snow->render_for(given.render).visibility_cutoff, 0.005);
  const WeatherSpec own = parse({{"effects", {{"snow", {{"rate_mm_h", 2.5}, {"visibility_cutoff", 0.02}}}}}});
  EXPECT_EQ(*own.snow->visibility_cutoff, 0.02);
  // The resolved spec says so and parses back to it; one written before the default (a render block
  // with its cutoff, no effect key) keeps its cutoff.
  EXPECT_EQ(s.to_json()["effects"]["snow"]["visibility_cutoff"], kPhysicalSnowVisibilityCutoff);
  EXPECT_EQ(*parse(s.to_json()).snow->visibility_cutoff, kPhysicalSnowVisibilityCutoff);
  Json old = s.to_json();
  old["effects"]["snow"].erase("visibility_cutoff");
  EXPECT_FALSE(parse(old).snow->visibility_cutoff.has_value());
  const Json bad = {{"snow", {{"rate_mm_h", 2.5}, {"visibility_cutoff", 0}}}};
  EXPECT_THROW(parse({{"effects", bad}}), InputError);
}

TEST(Photometry, LensDropCoverGlassDefaultsByStyleAndAttach) {
  auto parse = [](const Json& j) { return parse_weather_spec(JsonReader(j, "spec.json")); };
  const Json lens = {{"lens_droplets", {{"count", 5}}}};
  // Physical, on the lens: a 1 mm cover glass (the Cycles reference's); paper and window: thin.
  const WeatherSpec physical = parse({{"effects", lens}});
  EXPECT_EQ(physical.lens_droplets->glass_thickness_mm, 1.0);
  EXPECT_EQ(physical.to_json()["effects"]["lens_droplets"]["glass_thickness_mm"], 1.0);
  EXPECT_EQ(parse({{"style", "paper"}, {"effects", lens}}).lens_droplets->glass_thickness_mm, 0.0);
  const Json window = {{"lens_droplets", {{"count", 5}, {"attach", "window"}}}};
  EXPECT_EQ(parse({{"effects", window}}).lens_droplets->glass_thickness_mm, 0.0);
  // Given values win; a glass nearer than 4 mm gets a quarter of its distance, so the default is valid.
  const Json thin = {{"lens_droplets", {{"count", 5}, {"glass_thickness_mm", 0}}}};
  EXPECT_EQ(parse({{"effects", thin}}).lens_droplets->glass_thickness_mm, 0.0);
  const Json near = {{"lens_droplets", {{"count", 5}, {"glass_distance_m", 0.002}}}};
  EXPECT_DOUBLE_EQ(parse({{"effects", near}}).lens_droplets->glass_thickness_mm, 0.5);
  // The resolved spec parses back to the same glass.
  EXPECT_EQ(parse(physical.to_json()).lens_droplets->glass_thickness_mm, 1.0);
}

TEST(Photometry, LensDropCameraRadianceDefaultsByStyleAndAttach) {
  auto parse = [](const Json& j) { return parse_weather_spec(JsonReader(j, "spec.json")); };
  const Json lens = {{"lens_droplets", {{"count", 5}}}};
  // Physical, on the lens: light sent back towards the camera meets its dark front (agrees with a
  // Cycles camera body); paper: the environment, as its suite was generated.
  const WeatherSpec physical = parse({{"effects", lens}});
  ASSERT_TRUE(physical.lens_droplets->camera_radiance.has_value());
  EXPECT_EQ(*physical.lens_droplets->camera_radiance, (std::array<double, 3>{0, 0, 0}));
  EXPECT_EQ(physical.to_json()["effects"]["lens_droplets"]["camera_radiance"], Json::array({0.0, 0.0, 0.0}));
  const WeatherSpec paper = parse({{"style", "paper"}, {"effects", lens}});
  EXPECT_FALSE(paper.lens_droplets->camera_radiance.has_value());
  EXPECT_EQ(paper.to_json()["effects"]["lens_droplets"]["camera_radiance"], "environment");
  // A window: the room lies behind the camera, not its body.
  const Json window = {{"lens_droplets", {{"count", 5}, {"attach", "window"}}}};
  EXPECT_FALSE(parse({{"effects", window}}).lens_droplets->camera_radiance.has_value());
  const Json env = {{"lens_droplets", {{"count", 5}, {"camera_radiance", "environment"}}}};
  EXPECT_FALSE(parse({{"effects", env}}).lens_droplets->camera_radiance.has_value());
  const Json grey = {{"lens_droplets", {{"count", 5}, {"camera_radiance", {0.1, 0.1, 0.1}}}}};
  const WeatherSpec g = parse({{"style", "paper"}, {"effects", grey}});
  EXPECT_EQ(*g.lens_droplets->camera_radiance, (std::array<double, 3>{0.1, 0.1, 0.1}));
  // The resolved spec parses back to the same choice.
  EXPECT_FALSE(parse(paper.to_json()).lens_droplets->camera_radiance.has_value());
  EXPECT_TRUE(parse(physical.to_json()).lens_droplets->camera_radiance.has_value());
  for (const Json& v : {Json("body"), Json::array({-1.0, 0.0, 0.0}), Json::array({0.0, 0.0})}) {
    const Json bad = {{"lens_droplets", {{"count", 5}, {"camera_radiance", v}}}};
    EXPECT_THROW(parse({{"effects", bad}}), InputError) << v.dump();
  }
}

}  // namespace
}  // namespace weathergs::generator
