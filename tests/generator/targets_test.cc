// Named intensities, the paper style (exaggerated world-space particles + the per-view 2D overlay),
// the restoration targets and the perceptible lens mask (docs/generator.md).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "generator/overlay.h"
#include "generator/physics_constants.h"
#include "generator/weather.h"
#include "tests/core/test_util.h"
#include "tests/generator/test_scene.h"

namespace weathergs::generator {
namespace {

namespace fs = std::filesystem;
using testing::SceneOptions;
using testing::TempDir;

Json run(const std::string& in, const Json& spec, const std::string& out, WeatherRunOptions o = {}) {
  return run_weather(in, JsonReader(spec, "spec.json"), out, o);
}

std::string input_error(const Json& spec) {
  try {
    parse_weather_spec(JsonReader(spec, "spec.json"));
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

double mean_abs(const Image& a, const Image& b) {
  double s = 0;
  for (size_t i = 0; i < a.data.size(); ++i) s += std::abs(double(a.data[i]) - b.data[i]);
  return s / double(a.data.size());
}

TEST(NamedIntensity, RatesFollowTheClassBounds) {
  // Geometric means of the documented class bounds (physics_constants.h).
  EXPECT_NEAR(intensity_rate_mm_h(Species::kRain, Intensity::kLight), std::sqrt(0.25 * 2.5), 1e-12);
  EXPECT_NEAR(intensity_rate_mm_h(Species::kRain, Intensity::kModerate), 5.0, 1e-12);
  EXPECT_NEAR(intensity_rate_mm_h(Species::kRain, Intensity::kHeavy), std::sqrt(500.0), 1e-12);
  EXPECT_NEAR(intensity_rate_mm_h(Species::kRain, Intensity::kViolent), std::sqrt(5000.0), 1e-12);
  EXPECT_NEAR(intensity_rate_mm_h(Species::kSnow, Intensity::kHeavy), 10.0, 1e-12);
  // Each named rate lies inside its class.
  for (Species sp : {Species::kRain, Species::kSnow}) {
    const double* b = sp == Species::kRain ? physics::kRainClassBounds_mm_h : physics::kSnowClassBounds_mm_h;
    for (int i = 0; i < 4; ++i) {
      const double r = intensity_rate_mm_h(sp, Intensity(i));
      EXPECT_GT(r, b[i]);
      EXPECT_LT(r, b[i + 1]);
    }
  }
  const WeatherSpec s = parse_weather_spec(
      JsonReader(Json::parse(R"({"effects": {"rain": {"intensity": "violent"}, "snow": {"intensity": "light"}}})"), "s"));
  EXPECT_NEAR(s.rain->species.rate_mm_h, std::sqrt(5000.0), 1e-12);
  EXPECT_NEAR(s.snow->species.rate_mm_h, 0.5, 1e-12);
  // The resolved spec records both, and parses back to the same rate.
  const Json resolved = s.to_json();
  EXPECT_EQ(resolved["effects"]["rain"]["intensity"], "violent");
  const WeatherSpec again = parse_weather_spec(JsonReader(resolved, "resolved"));
  EXPECT_EQ(again.rain->species.rate_mm_h, s.rain->species.rate_mm_h);
  // Errors name the key.
  EXPECT_NE(input_error(Json::parse(R"({"effects": {"rain": {"intensity": "biblical"}}})")).find("/effects/rain/intensity"),
            std::string::npos);
  EXPECT_NE(input_error(Json::parse(R"({"effects": {"rain": {"intensity": "heavy", "rate_mm_h": 3}}})")).find("give one"),
            std::string::npos);
  EXPECT_NE(input_error(Json::parse(R"({"effects": {"rain": {"wind_m_s": [1, 0, 0]}}})")).find("rate_mm_h"),
            std::string::npos);
}

TEST(PaperStyle, DefaultsAreRecordedAndPhysicalRejectsPaperBlocks) {
  const Json paper = Json::parse(R"({"style": "paper", "effects": {"rain": {"intensity": "heavy"}}})");
  const WeatherSpec s = parse_weather_spec(JsonReader(paper, "s"));
  EXPECT_EQ(s.style, WeatherStyle::kPaper);
  EXPECT_EQ(s.rain->species.size_scale, 6.0);
  EXPECT_EQ(s.render.visibility_cutoff, 0.1);
  ASSERT_TRUE(s.rain->overlay.has_value());
  EXPECT_NEAR(s.rain->overlay->rate_scale, 1.0, 1e-12);  // heavy is the overlay's reference rate
  EXPECT_EQ(s.render.max_distance_m, 15.0);
  const Json resolved = s.to_json();
  EXPECT_EQ(resolved["style"], "paper");
  EXPECT_EQ(resolved["effects"]["rain"]["paper"]["overlay"]["count_per_mpx"], 10000.0);
  // The override to physical drops every exaggeration; a paper block in a physical spec is an error.
  const WeatherSpec phys = parse_weather_spec(JsonReader(paper, "s"), WeatherStyle::kPhysical);
  EXPECT_EQ(phys.rain->species.size_scale, 1.0);
  EXPECT_FALSE(phys.rain->overlay.has_value());
  EXPECT_NE(input_error(Json::parse(R"({"effects": {"rain": {"rate_mm_h": 5, "paper": {"size_scale": 3}}}})"))
                .find("style"),
            std::string::npos);
  EXPECT_NE(input_error(Json::parse(
                R"({"style": "paper", "effects": {"rain": {"rate_mm_h": 5, "paper": {"overlay": {"radius_px": 3}}}}})"))
                .find("unknown key"),
            std::string::npos);  // radius_px is a snow key
}

TEST(Overlay, DeterministicPerViewAndNotMultiViewConsistent) {
  OverlayOptions o = OverlayOptions::defaults(Species::kRain);
  const Image a = render_overlay_alpha(o, 7, "001", 120, 80);
  const Image b = render_overlay_alpha(o, 7, "001", 120, 80);
  const Image c = render_overlay_alpha(o, 7, "002", 120, 80);
  EXPECT_EQ(a.data, b.data);
  EXPECT_GT(mean_abs(a, c), 1e-3) << "each view draws its own layer";
  double mean = 0;
  for (float v : a.data) {
    ASSERT_TRUE(std::isfinite(v));
    ASSERT_GE(v, 0.f);
    ASSERT_LE(v, 1.f);
    mean += v;
  }
  // At the 600-pixel reference width the default rain layer covers a few percent of the image.
  const Image full = render_overlay_alpha(o, 7, "001", 600, 400);
  double full_mean = 0;
  for (float v : full.data) full_mean += v;
  EXPECT_GT(full_mean / double(full.data.size()), 0.01);
  EXPECT_GT(mean, 0.0);
  // Count 0 draws nothing; a tiny image and extreme sizes stay finite.
  o.count_per_mpx = 0;
  for (float v : render_overlay_alpha(o, 7, "001", 50, 40).data) ASSERT_EQ(v, 0.f);
  OverlayOptions snow = OverlayOptions::defaults(Species::kSnow);
  snow.radius_px = {50, 200};
  for (float v : render_overlay_alpha(snow, 1, "x", 1, 1).data) ASSERT_TRUE(std::isfinite(v));
  snow.count_per_mpx = 1e6;
  snow.rate_scale = 1e4;
  EXPECT_THROW(render_overlay_alpha(snow, 1, "x", 4000, 3000), InputError);
}

TEST(Targets, NoParticleTargetIsExactAndLensOnlyMatchesClean) {
  TempDir tmp;
  testing::make_clean_dataset(tmp / "clean", SceneOptions{});
  const Json spec = Json::parse(R"({"seed": 3, "style": "paper", "effects": {"rain": {"intensity": "heavy",
      "wind_m_s": [1, 0, 0]}}})");
  WeatherRunOptions o;
  o.write_targets = true;
  run(tmp / "clean", spec, tmp / "out", o);
  const Dataset d = read_dataset(tmp / "out");
  for (const Camera& c : d.cameras) {
    const Image img = to_linear(read_image(d.path(ImageKind::kImages, c.name)));
    const Image target = to_linear(read_image(d.path(ImageKind::kTargetNoParticles, c.name)));
    const Image clean = to_linear(read_image(d.path(ImageKind::kClean, c.name)));
    const Image alpha = read_image(d.layer_path("particle_alpha", c.name));
    // No fog and no drops here: the no-particle target is the clean view, byte for byte, and so is
    // the lens-only target.
    EXPECT_EQ(read_file(d.path(ImageKind::kTargetNoParticles, c.name)), read_file(d.path(ImageKind::kClean, c.name)));
    EXPECT_EQ(read_file(d.path(ImageKind::kTargetLensOnly, c.name)), read_file(d.path(ImageKind::kClean, c.name)));
    // Where no particle reached, the weathered view is the target; where one did, it differs.
    int touched = 0, untouched_equal = 0, untouched = 0;
    for (int y = 0; y < c.height; ++y)
      for (int x = 0; x < c.width; ++x) {
        bool same = true;
        for (int ch = 0; ch < 3; ++ch) same &= img.at(x, y, ch) == target.at(x, y, ch);
        if (alpha.at(x, y) == 0.f) {
          ++untouched;
          untouched_equal += same;
        } else if (alpha.at(x, y) > 0.2f) {
          touched += !same;
        }
      }
    EXPECT_EQ(untouched_equal, untouched) << c.name;
    EXPECT_GT(touched, 0) << c.name;
    EXPECT_GT(mean_abs(img, clean), 0.005) << "the paper style is visible in view " << c.name;
  }
  // Targets do not change the weathered images.
  run(tmp / "clean", spec, tmp / "plain");
  const Dataset p = read_dataset(tmp / "plain");
  for (const Camera& c : p.cameras)
    EXPECT_EQ(read_file(p.path(ImageKind::kImages, c.name)), read_file(d.path(ImageKind::kImages, c.name)));
  EXPECT_FALSE(fs::exists(p.dir(ImageKind::kTargetNoParticles)));
}

TEST(Targets, WithLensDropsTheTargetsKeepTheSameDrops) {
  TempDir tmp;
  testing::make_clean_dataset(tmp / "clean", SceneOptions{});
  const Json spec = Json::parse(R"({"seed": 5, "effects": {"rain": {"rate_mm_h": 50},
      "lens_droplets": {"count": 12, "radius_mm": [0.8, 2.0]}}})");
  WeatherRunOptions o;
  o.write_targets = true;
  run(tmp / "clean", spec, tmp / "out", o);
  const Dataset d = read_dataset(tmp / "out");
  for (const Camera& c : d.cameras) {
    const Image lens_only = read_image(d.path(ImageKind::kTargetLensOnly, c.name));
    const Image no_particles = read_image(d.path(ImageKind::kTargetNoParticles, c.name));
    const Image clean = read_image(d.path(ImageKind::kClean, c.name));
    const Image coverage = read_image(d.layer_path(layout::kLensCoverageLayer, c.name));
    const Image mask = read_mask(d.path(ImageKind::kLensMask, c.name));
    // Without fog the no-particle target is exactly the lens-only target (same drops, same seed).
    EXPECT_EQ(read_file(d.path(ImageKind::kTargetLensOnly, c.name)), read_file(d.path(ImageKind::kTargetNoParticles, c.name)));
    // Outside the drops' coverage the lens-only target is the clean view; the perceptible mask marks
    // only pixels that the drops changed by more than 4 levels.
    for (int y = 0; y < c.height; ++y)
      for (int x = 0; x < c.width; ++x) {
        float change = 0;
        for (int ch = 0; ch < 3; ++ch) change = std::max(change, std::abs(lens_only.at(x, y, ch) - clean.at(x, y, ch)));
        if (coverage.at(x, y) == 0.f) { ASSERT_EQ(change, 0.f) << c.name << " " << x << "," << y; }
        if (mask.at(x, y) > 0.5f) { ASSERT_GT(change * 255.f, 3.5f) << c.name << " " << x << "," << y; }
      }
    (void)no_particles;
  }
}

}  // namespace
}  // namespace weathergs::generator
