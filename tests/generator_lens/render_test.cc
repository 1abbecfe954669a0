// Per-view rendering: zero drops, energy, determinism (threads, view order), lens vs window attach,
// hard cases, defocus, masks, and triangulated vs analytic caps.
#include <gtest/gtest.h>

#include <cmath>

#include "core/error.h"
#include "core/parallel.h"
#include "core/thin_lens.h"
#include "generator/lens/lens_render.h"
#include "tests/generator_lens/lens_test_util.h"

namespace weathergs::generator::lens {
namespace {

using testing::test_camera;
using testing::test_image;

LensDropletSpec spec_from(const std::string& text) {
  Json j = Json::parse(text);
  return parse_lens_droplet_spec(JsonReader(j, "test"));
}

Camera moved(Camera c, const std::string& name, const Eigen::Vector3d& t, double yaw_rad = 0) {
  c.name = name;
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
  m.topRightCorner<3, 1>() = t;
  c.camera_from_world = m;
  return c;
}

double max_abs_diff(const Image& a, const Image& b) {
  double m = 0;
  for (size_t i = 0; i < a.data.size(); ++i) m = std::max(m, double(std::abs(a.data[i] - b.data[i])));
  return m;
}

double mean(const Image& a) {
  double s = 0;
  for (float v : a.data) s += v;
  return s / a.data.size();
}

bool all_finite_in(const Image& a, float lo, float hi) {
  for (float v : a.data)
    if (!std::isfinite(v) || v < lo || v > hi) return false;
  return true;
}

TEST(LensRenderTest, ZeroDropsGiveIdenticalOutputAndNoEmbreeDevice) {
  const Camera cam = test_camera();
  const Image img = test_image(cam.width, cam.height);
  const int64_t devices = EmbreeDevice::num_created();
  LensDropletRenderer r(spec_from(R"({"count": 0})"), 7, cam);
  EXPECT_FALSE(r.has_embree_device());
  LensViewResult out = r.render(img, cam, 0.0);
  EXPECT_EQ(EmbreeDevice::num_created(), devices);
  EXPECT_EQ(out.image.data, img.data);
  EXPECT_EQ(mean(out.coverage), 0.0);
  EXPECT_EQ(mean(out.mask), 0.0);
  EXPECT_TRUE(out.drops["drops"].empty());
  EXPECT_EQ(out.camera_rays, 0);

  // Drops that exist but are all out of sight (a window behind the camera) change nothing either.
  LensDropletSpec behind = spec_from(R"({"count": 20, "attach": "window", "window": {
      "center_world": [0, 0, -1], "normal_world": [0, 0, 1], "up_world": [0, -1, 0], "size_m": [0.2, 0.2]}})");
  LensDropletRenderer rb(behind, 7, cam);
  LensViewResult ob = rb.render(img, cam, 0.0);
  EXPECT_EQ(ob.image.data, img.data);
  EXPECT_EQ(ob.camera_rays, 0);
}

TEST(LensRenderTest, SkyEnvironmentLightsTheUnfollowedPaths) {
  // "sky": the unfollowed paths take the given sky radiance. A uniform scene under a sky of the same
  // radiance stays uniform; a brighter sky brightens the drops (and only them); no sky is a check.
  const Camera cam = test_camera();
  Image img(cam.width, cam.height, 3, ColorSpace::kLinear, 0.3f);
  const LensDropletSpec spec = spec_from(R"({"count": 40, "environment_radiance": "sky", "defocus": false})");
  EXPECT_TRUE(spec.environment_sky);
  const Eigen::Vector3f same = Eigen::Vector3f::Constant(0.3f), bright = Eigen::Vector3f::Constant(0.9f);
  LensViewResult a = LensDropletRenderer(spec, 3, cam).render(img, cam, 0.0, &same);
  EXPECT_LT(max_abs_diff(a.image, img), 1e-5);
  LensViewResult b = LensDropletRenderer(spec, 3, cam).render(img, cam, 0.0, &bright);
  EXPECT_GT(mean(b.image), mean(img) + 1e-4);
  for (size_t p = 0; p < img.num_pixels(); ++p)
    if (b.coverage.data[p] == 0) { ASSERT_EQ(b.image.data[p * 3], img.data[p * 3]) << p; }
  EXPECT_THROW(LensDropletRenderer(spec, 3, cam).render(img, cam, 0.0), InternalError);
}

TEST(LensRenderTest, ConstantSceneIsUnchangedEnergyIsConserved) {
  // With the environment = the view's mean radiance, every path's weights sum to 1, so a uniform
  // scene stays uniform through drops, reflections, cut paths and the blur.
  Camera cam = test_camera();
  cam.f_number = 2.8;
  cam.focal_length_mm = 4;
  cam.focus_distance_m = 5;
  Image img(cam.width, cam.height, 3, ColorSpace::kLinear, 0.6f);
  LensViewResult out = LensDropletRenderer(spec_from(R"({"count": 40, "contact_angle_deg": [10, 170]})"), 3, cam)
                           .render(img, cam, 0.0);
  EXPECT_GT(out.water_rays, 1000);
  EXPECT_GT(out.blur_diameter_px, 1);
  // float accumulation of <= 64 weighted terms and a normalized blur kernel: ~1e-6 relative.
  EXPECT_LT(max_abs_diff(out.image, img), 1e-5);
  EXPECT_TRUE(all_finite_in(out.coverage, 0, 1));
}

TEST(LensRenderTest, DeterministicAcrossThreadCountsAndViewOrder) {
  const Camera a = test_camera(160, 120, 140, "a");
  const Camera b = moved(test_camera(160, 120, 140, "b"), "b", {0.1, 0, 0}, 0.2);
  const Image ia = test_image(a.width, a.height);
  Image ib = ia;
  for (float& v : ib.data) v = 1 - v;
  const LensDropletSpec spec = spec_from(R"({"count": 30, "samples_per_pixel": 5, "contact_angle_deg": [20, 150]})");
  const int before = num_threads();
  set_num_threads(1);
  LensDropletRenderer r1(spec, 11, a);
  LensViewResult a1 = r1.render(ia, a, 0.0), b1 = r1.render(ib, b, 0.5);
  set_num_threads(2);
  LensDropletRenderer r2(spec, 11, a);
  LensViewResult b2 = r2.render(ib, b, 0.5), a2 = r2.render(ia, a, 0.0);
  set_num_threads(before);
  EXPECT_EQ(a1.image.data, a2.image.data);
  EXPECT_EQ(a1.coverage.data, a2.coverage.data);
  EXPECT_EQ(b1.image.data, b2.image.data);
  EXPECT_EQ(a1.drops.dump(), a2.drops.dump());
  EXPECT_EQ(b1.drops.dump(), b2.drops.dump());
  EXPECT_GT(a1.water_rays, 0);
  // A different seed gives different drops.
  LensViewResult other = LensDropletRenderer(spec, 12, a).render(ia, a, 0.0);
  EXPECT_NE(other.coverage.data, a1.coverage.data);
}

TEST(LensRenderTest, LensAttachedDropsAreIdenticalAcrossViews) {
  const Camera a = test_camera(160, 120, 140, "a");
  const Camera b = moved(a, "b", {0.5, -0.2, 0.3}, 0.4);
  const Image img = test_image(a.width, a.height);
  LensDropletRenderer r(spec_from(R"({"count": 25, "samples_per_pixel": 1})"), 5, a);
  LensViewResult ra = r.render(img, a, 1.0), rb = r.render(img, b, 1.0);
  EXPECT_EQ(ra.drops["drops"].dump(), rb.drops["drops"].dump());
  EXPECT_GT(ra.drops["drops"].size(), 3u);
  // Per-pixel noise is keyed on the view name, so coverage matches up to one sample per pixel; its
  // total agrees to the sampling noise.
  EXPECT_NEAR(mean(ra.coverage), mean(rb.coverage), 0.01);

  // Sliding: large drops move down the glass by speed * time, pinned small ones stay.
  LensDropletRenderer s(spec_from(R"({"count": 25, "slide_speed_mm_s": 1, "slide_min_radius_mm": 1.5})"), 5, a);
  Json d0 = s.render(img, a, 0.0).drops["drops"], d1 = s.render(img, a, 2.0).drops["drops"];
  int moved_down = 0, pinned = 0;
  for (const Json& p0 : d0) {
    for (const Json& p1 : d1) {
      if (p1["id"] != p0["id"]) continue;
      const double dy = p1["base_center_camera_m"][1].get<double>() - p0["base_center_camera_m"][1].get<double>();
      if (p0["outline_radius_mm"].get<double>() >= 1.5) {
        EXPECT_NEAR(dy, 2e-3, 1e-12);
        ++moved_down;
      } else {
        EXPECT_EQ(dy, 0);
        ++pinned;
      }
    }
  }
  EXPECT_GT(moved_down, 0);
  EXPECT_GT(pinned, 0);
}

TEST(LensRenderTest, WindowAttachedDropsShowParallax) {
  const Camera a = test_camera(160, 120, 140, "a");
  const Camera b = moved(a, "b", {-0.01, 0, 0});  // camera 1 cm to the right
  const Image img = test_image(a.width, a.height);
  LensDropletSpec spec = resolve_lens_droplet_spec(
      spec_from(R"({"count": 40, "attach": "window", "glass_distance_m": 0.1})"), a);
  ASSERT_TRUE(spec.window.has_value());
  EXPECT_NEAR(spec.window->center_world.z(), 0.1, 1e-12);
  LensDropletRenderer r(spec, 5, a);
  Json da = r.render(img, a, 0.0).drops["drops"], db = r.render(img, b, 0.0).drops["drops"];
  int matched = 0;
  for (const Json& p : da)
    for (const Json& q : db)
      if (p["id"] == q["id"]) {
        // x_cam shifts by -1 cm: u shifts by fx * 0.01 / 0.1 = 14 px to the left.
        EXPECT_NEAR(q["center_px"][0].get<double>() - p["center_px"][0].get<double>(), -14.0, 1e-6);
        ++matched;
      }
  EXPECT_GT(matched, 5);
}

TEST(LensRenderTest, WindowDropsSlideDownTheWorld) {
  // A pane facing a camera that looks along world +y (camera y = -world z): large drops slide along
  // world -z, which is image down (+y in the camera frame), at the given speed.
  Camera cam = test_camera(160, 120, 140, "a");
  Eigen::Matrix3d r;
  r << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  cam.camera_from_world.topLeftCorner<3, 3>() = r;
  const Image img = test_image(cam.width, cam.height);
  LensDropletSpec spec = resolve_lens_droplet_spec(
      spec_from(R"({"count": 30, "attach": "window", "glass_distance_m": 0.1, "slide_speed_mm_s": 5,
                   "slide_min_radius_mm": 1.0})"),
      cam);
  EXPECT_NEAR(spec.window->up_world.z(), 1.0, 1e-12);
  LensDropletRenderer renderer(spec, 3, cam);
  Json d0 = renderer.render(img, cam, 0.0).drops["drops"], d1 = renderer.render(img, cam, 0.5).drops["drops"];
  int slid = 0;
  for (const Json& p : d0)
    for (const Json& q : d1)
      if (p["id"] == q["id"] && p["outline_radius_mm"].get<double>() >= 1.0) {
        EXPECT_NEAR(q["base_center_camera_m"][1].get<double>() - p["base_center_camera_m"][1].get<double>(), 2.5e-3,
                    1e-12);
        EXPECT_NEAR(q["base_center_camera_m"][0].get<double>(), p["base_center_camera_m"][0].get<double>(), 1e-12);
        ++slid;
      }
  EXPECT_GT(slid, 3);
}

TEST(LensRenderTest, ViewThroughADropIsInverted) {
  // Left half dark, right half bright; a hemispherical drop on the axis shows the bright half on its
  // left side.
  Camera cam = test_camera(160, 120, 140);
  Image img(cam.width, cam.height, 3, ColorSpace::kLinear, 0.1f);
  for (int y = 0; y < cam.height; ++y)
    for (int x = cam.width / 2; x < cam.width; ++x)
      for (int c = 0; c < 3; ++c) img.at(x, y, c) = 0.9f;
  LensDropletSpec spec = resolve_lens_droplet_spec(
      spec_from(R"({"count": 1, "radius_mm": 4, "contact_angle_deg": 90, "attach": "window",
                   "window": {"center_world": [0, 0, 0.03], "normal_world": [0, 0, 1], "up_world": [0, -1, 0],
                   "size_m": [1e-9, 1e-9]}, "samples_per_pixel": 4})"),
      cam);
  LensViewResult out = LensDropletRenderer(spec, 1, cam).render(img, cam, 0.0);
  // The drop spans +-18.7 px around the center (fx * 4 mm / 3 cm).
  const int cx = cam.width / 2, cy = cam.height / 2;
  EXPECT_EQ(out.coverage.at(cx - 8, cy), 1.f);
  EXPECT_EQ(out.coverage.at(cx + 8, cy), 1.f);
  EXPECT_GT(out.image.at(cx - 8, cy, 0), 0.6f) << "left of center sees the bright right half";
  EXPECT_LT(out.image.at(cx + 8, cy, 0), 0.4f) << "right of center sees the dark left half";
  EXPECT_EQ(out.coverage.at(cx - 30, cy), 0.f);
  EXPECT_EQ(out.image.at(cx - 30, cy, 0), img.at(cx - 30, cy, 0));
}

TEST(LensRenderTest, HardCasesStayFinite) {
  const Camera cam = test_camera(120, 90, 100);
  const Image img = test_image(cam.width, cam.height);
  for (const char* text : {
           R"({"count": 30, "contact_angle_deg": 0.001})",          // flat films
           R"({"count": 30, "contact_angle_deg": 179.999})",        // near-spheres on a point
           R"({"count": 200, "radius_mm": [2, 6], "contact_angle_deg": [5, 175]})",  // heavy overlap, borders
           R"({"count": 3, "radius_mm": 400, "contact_angle_deg": 60})",  // drops larger than the image
           R"({"count": 20, "glass_tilt_deg": [60, -45], "drop_side": "camera"})",
           R"({"count": 20, "geometry": "triangles", "cap_segments": 6, "max_bounces": 0})",
       }) {
    SCOPED_TRACE(text);
    LensViewResult out = LensDropletRenderer(spec_from(text), 9, cam).render(img, cam, 0.0);
    EXPECT_TRUE(all_finite_in(out.image, 0, 1.0001f));
    EXPECT_TRUE(all_finite_in(out.coverage, 0, 1));
    EXPECT_GT(out.water_rays, 0);
  }
  // A drop larger than the image covers every pixel.
  LensViewResult big = LensDropletRenderer(spec_from(R"({"count": 1, "radius_mm": 1000,
      "contact_angle_deg": 30, "sampling_margin": 0, "mask_rule": "coverage"})"), 2, cam).render(img, cam, 0.0);
  EXPECT_EQ(mean(big.mask), 1.0);
  // Nearly flat drops leave the image as it was, up to the ~4 % Fresnel loss at two interfaces.
  LensViewResult flat = LensDropletRenderer(spec_from(R"({"count": 40, "contact_angle_deg": 0.01,
      "radius_mm": [1, 3]})"), 2, cam).render(img, cam, 0.0);
  EXPECT_GT(mean(flat.coverage), 0.05);
  EXPECT_LT(max_abs_diff(flat.image, img), 0.05);
}

TEST(LensRenderTest, DefocusFollowsTheThinLensAndKeepsCoverageMass) {
  Camera cam = test_camera(160, 120, 140);
  cam.f_number = 8;
  cam.focal_length_mm = 4;
  cam.focus_distance_m = 3;
  // c = fx * (f / N) * |S2 - S1| / (S2 (S1 - f)) = 140 * 0.5e-3 * 2.97 / (0.03 * 2.996) = 2.313 px.
  const double coc = thin_lens_of(cam)->coc_diameter_px(cam.fx, 0.03);
  EXPECT_NEAR(coc, 140 * 0.5e-3 * 2.97 / (0.03 * 2.996), 1e-12);
  EXPECT_NEAR(coc, 2.3131, 1e-4);
  EXPECT_FALSE(thin_lens_of(test_camera()).has_value());  // no thin-lens data: pinhole
  cam.f_number = 1.4;  // 13.2 px
  const Image img = test_image(cam.width, cam.height);
  // Drops well inside the frame, so the blur moves no coverage across the border.
  const char* text = R"({"count": 6, "radius_mm": [0.6, 1.0], "sampling_margin": -0.0, "attach": "window",
      "window": {"center_world": [0, 0, 0.03], "normal_world": [0, 0, 1], "up_world": [0, -1, 0],
      "size_m": [0.016, 0.01]}, "defocus": DEFOCUS})";
  auto with = [&](const char* d) {
    std::string s = text;
    s.replace(s.find("DEFOCUS"), 7, d);
    return LensDropletRenderer(spec_from(s), 4, cam).render(img, cam, 0.0);
  };
  LensViewResult sharp = with("false"), blurred = with("true");
  EXPECT_EQ(sharp.blur_diameter_px, 0);
  EXPECT_NEAR(blurred.blur_diameter_px, thin_lens_of(cam)->coc_diameter_px(cam.fx, 0.03), 1e-9);
  EXPECT_NEAR(mean(blurred.coverage), mean(sharp.coverage), 1e-4 * mean(sharp.coverage) + 1e-7);
  // Blurring spreads coverage: fewer fully covered pixels, more partially covered ones.
  auto count_if = [](const Image& c, float lo, float hi) {
    int n = 0;
    for (float v : c.data) n += v > lo && v < hi;
    return n;
  };
  EXPECT_GT(count_if(blurred.coverage, 0.01f, 0.99f), 2 * count_if(sharp.coverage, 0.01f, 0.99f));
  // A blur wider than 32 px is traced on 2x2-pixel cells: same coverage mass up to sampling noise
  // (a few hundred water samples per drop: ~5 %), and a uniform scene stays uniform.
  cam.focal_length_mm = 12;  // 39.8 px
  LensViewResult wide = with("true");
  EXPECT_GT(wide.blur_diameter_px, 32);
  EXPECT_EQ(wide.drops["trace_cell_px"], 2);
  EXPECT_NEAR(mean(wide.coverage), mean(sharp.coverage), 0.05 * mean(sharp.coverage));
  Image flat(cam.width, cam.height, 3, ColorSpace::kLinear, 0.3f);
  std::string flat_spec = text;
  flat_spec.replace(flat_spec.find("DEFOCUS"), 7, "true");
  EXPECT_LT(max_abs_diff(LensDropletRenderer(spec_from(flat_spec), 4, cam).render(flat, cam, 0.0).image, flat), 1e-5);
  // The default mask ("perceptible") marks exactly the pixels the drops change by more than 4 8-bit
  // levels; the "coverage" rule is the documented threshold of the blurred coverage.
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      float change = 0;
      for (int c = 0; c < 3; ++c) {
        auto q = [](float v) { return std::round(255.f * std::clamp(linear_to_srgb(v), 0.f, 1.f)); };
        change = std::max(change, std::abs(q(blurred.image.at(x, y, c)) - q(img.at(x, y, c))));
      }
      ASSERT_EQ(blurred.mask.at(x, y), change > 4.f ? 1.f : 0.f) << x << "," << y;
    }
  std::string coverage_spec = text;
  coverage_spec.replace(coverage_spec.find("DEFOCUS"), 7, R"(true, "mask_rule": "coverage")");
  const LensViewResult by_coverage = LensDropletRenderer(spec_from(coverage_spec), 4, cam).render(img, cam, 0.0);
  for (size_t i = 0; i < by_coverage.mask.data.size(); ++i)
    ASSERT_EQ(by_coverage.mask.data[i], by_coverage.coverage.data[i] >= 0.1f ? 1.f : 0.f);
}

TEST(LensRenderTest, TriangulatedCapsApproachAnalyticOnes) {
  const Camera cam = test_camera(160, 120, 140);
  const Image img = test_image(cam.width, cam.height);
  auto render = [&](const char* geometry, int segments) {
    std::string s = std::string(R"({"count": 20, "samples_per_pixel": 4, "geometry": ")") + geometry +
                    R"(", "cap_segments": )" + std::to_string(segments) + "}";
    return LensDropletRenderer(spec_from(s), 6, cam).render(img, cam, 0.0);
  };
  LensViewResult analytic = render("analytic", 48), coarse = render("triangles", 8),
                 fine = render("triangles", 96);
  auto rmse = [](const Image& a, const Image& b) {
    double s = 0;
    for (size_t i = 0; i < a.data.size(); ++i) s += std::pow(a.data[i] - b.data[i], 2);
    return std::sqrt(s / a.data.size());
  };
  EXPECT_NEAR(mean(fine.coverage), mean(analytic.coverage), 0.01 * mean(analytic.coverage));
  EXPECT_LT(rmse(fine.image, analytic.image), rmse(coarse.image, analytic.image));
}

TEST(LensRenderTest, RejectsBadInputs) {
  const Camera cam = test_camera();
  LensDropletRenderer r(spec_from(R"({"count": 3})"), 1, cam);
  Image srgb = test_image(cam.width, cam.height);
  srgb.space = ColorSpace::kSRGB;
  EXPECT_THROW(r.render(srgb, cam, 0), InputError);
  EXPECT_THROW(r.render(test_image(10, 10), cam, 0), InputError);
  Image nan = test_image(cam.width, cam.height);
  nan.data[5] = NAN;
  EXPECT_THROW(r.render(nan, cam, 0), InputError);
}

}  // namespace
}  // namespace weathergs::generator::lens

namespace weathergs::generator::lens {
namespace {

TEST(LensDiskBlurTest, ReducedResolutionMatchesTheFullDisk) {
  // A sparse layer of bright squares; a 96 px disk at full resolution vs at 1/3 resolution.
  cv::Mat layer(200, 260, CV_32FC2, cv::Scalar::all(0));
  for (int i = 0; i < 12; ++i) layer(cv::Rect(20 + 19 * i, 30 + 11 * i, 9, 6)).setTo(cv::Scalar(1.0, 0.5));
  cv::Mat exact = disk_blur(layer, 96, 1e9), fast = disk_blur(layer, 96, 32);
  ASSERT_EQ(fast.size(), layer.size());
  ASSERT_EQ(fast.type(), layer.type());
  // The blur keeps the layer's mass (inside the frame: the squares sit >= 48 px from the border
  // except a few, so compare the two blurs with each other).
  const cv::Scalar se = cv::sum(exact), sf = cv::sum(fast);
  EXPECT_NEAR(sf[0], se[0], 0.01 * se[0]);
  double max_exact = 0, max_diff = 0;
  cv::minMaxLoc(exact.reshape(1), nullptr, &max_exact);
  cv::Mat diff;
  cv::absdiff(exact, fast, diff);
  cv::minMaxLoc(diff.reshape(1), nullptr, &max_diff);
  // The extra 3 px box + tent on a 96 px disk moves its edge by ~1.5 px: <= 5 % of the peak.
  EXPECT_LT(max_diff, 0.05 * max_exact);
  // A single pixel spreads to a disk of the requested diameter.
  cv::Mat dot(101, 101, CV_32F, cv::Scalar(0));
  dot.at<float>(50, 50) = 1;
  cv::Mat disk = disk_blur(dot, 21, 1e9);
  EXPECT_NEAR(cv::sum(disk)[0], 1.0, 1e-5);
  EXPECT_GT(disk.at<float>(50, 59), 0);   // inside radius 10.5
  EXPECT_LT(std::abs(disk.at<float>(50, 62)), 1e-9);  // outside (DFT round-off only)
}

}  // namespace
}  // namespace weathergs::generator::lens
