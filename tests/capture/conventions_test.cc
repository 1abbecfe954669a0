// End-to-end check of the camera and depth conventions through Blender: small emissive markers at
// known world points must be drawn where cameras.json projects them, and depth must unproject onto
// the geometry (planar camera z, not ray length).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/dataset.h"
#include "core/image.h"
#include "capture/blender.h"
#include "capture/process.h"
#include "tests/core/test_util.h"

namespace weathergs::capture {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// The required bar for where Blender draws a projected point.
constexpr double kMaxMarkerErrorPx = 0.5;
// A ray through a pixel near the marker's center hits its sphere, so the unprojected depth lies on
// the sphere: distance to the center = radius up to float32 depth and mesh faceting (32x16 UV sphere:
// the flat faces sit up to r * (1 - cos(pi/16)) ~ 2% of r inside the true sphere).
constexpr double kSphereSurfaceTolerance = 0.004;  // meters, for r = 0.12 m
constexpr double kGroundTolerance = 0.01;          // meters: float32 depth at 2-15 m

std::string scene_path(const std::string& name) { return std::string(WEATHERGS_SOURCE_DIR) + "/scenes/" + name; }

TEST(ConventionsTest, MarkersAndDepthMatchCamerasJson) {
  if (find_executable("blender").empty()) GTEST_SKIP() << "blender not installed";
  SceneSpec scene = read_scene_spec(scene_path("tanabata.json"));
  // Large enough that a marker covers a few pixels; two views from different path positions.
  scene.profiles["conventions"] = ProfileSpec{"conventions", 192, 128, 16, 8, "eevee"};
  // Markers in the open street in front of the camera (the street is 8 m wide, lanterns hang at 4.3 m).
  const double r = 0.12;
  std::vector<Marker> markers = {{{-0.8, 1.0, 1.2}, r}, {{0.9, 1.5, 2.0}, r}, {{0.0, 2.5, 1.5}, r},
                                 {{-0.5, 3.0, 2.4}, r}, {{0.6, 0.5, 1.0}, r}};
  TempDir tmp;
  BlenderOptions options;
  options.script = testing::blender_script();
  options.max_views = 3;
  const std::string out = tmp / "clean";
  RenderSummary summary = render_clean_dataset(scene, "clear", "conventions", out, options, markers);
  EXPECT_EQ(summary.views, 3);

  Dataset ds = read_dataset(out);
  ASSERT_EQ(ds.cameras.size(), 3u);
  int checked = 0;
  double sum_err = 0, max_err = 0;
  for (const Camera& cam : ds.cameras) {
    const Image img = read_image(ds.path(ImageKind::kClean, cam.name));
    const Image depth = read_depth(ds.path(ImageKind::kDepth, cam.name));
    // Magenta-ness of a pixel: the markers are sRGB (1, 0, 1); the scene has no such color.
    auto magenta = [&](int x, int y) {
      return std::min(img.at(x, y, 0), img.at(x, y, 2)) - img.at(x, y, 1);
    };
    for (const Marker& m : markers) {
      auto uv = cam.project(m.p_world);
      ASSERT_TRUE(uv.has_value());
      const int win = 7;
      if (uv->x() < win || uv->y() < win || uv->x() > cam.width - win || uv->y() > cam.height - win) continue;
      // Weighted centroid of the marker's pixels in a window around the prediction; weights below
      // half coverage are dropped so that the textured background adds nothing.
      double sw = 0, su = 0, sv = 0;
      int best_x = -1, best_y = -1;
      double best = 0;
      for (int y = int(uv->y()) - win; y <= int(uv->y()) + win; ++y)
        for (int x = int(uv->x()) - win; x <= int(uv->x()) + win; ++x) {
          const double w = magenta(x, y);
          if (w < 0.5) continue;
          sw += w;
          su += w * (x + 0.5);
          sv += w * (y + 0.5);
          if (w > best) best = w, best_x = x, best_y = y;
        }
      ASSERT_GT(sw, 3.0) << "marker at " << m.p_world.transpose() << " not found in view " << cam.name;
      const Eigen::Vector2d found(su / sw, sv / sw);
      const double err = (found - *uv).norm();
      EXPECT_LT(err, kMaxMarkerErrorPx) << "view " << cam.name << " marker " << m.p_world.transpose()
                                        << " projected " << uv->transpose() << " drawn " << found.transpose();
      sum_err += err;
      max_err = std::max(max_err, err);
      ++checked;
      // Depth at the marker's central pixel unprojects onto the sphere's surface.
      const int px = int(std::floor(uv->x())), py = int(std::floor(uv->y()));
      const double z = depth.at(px, py);
      ASSERT_TRUE(std::isfinite(z));
      const Eigen::Vector3d p = cam.unproject({px + 0.5, py + 0.5}, z);
      EXPECT_NEAR((p - m.p_world).norm(), r, kSphereSurfaceTolerance)
          << "view " << cam.name << " pixel " << px << "," << py << " depth " << z;
      (void)best_x, (void)best_y;
    }
    // The street's paving (top at z = 0) fills the bottom rows around the image center.
    int ground = 0;
    for (int y = cam.height - 6; y < cam.height; ++y)
      for (int x = cam.width / 2 - 10; x < cam.width / 2 + 10; ++x) {
        const double z = depth.at(x, y);
        ASSERT_TRUE(std::isfinite(z));
        const Eigen::Vector3d p = cam.unproject({x + 0.5, y + 0.5}, z);
        EXPECT_NEAR(p.z(), 0.0, kGroundTolerance) << "view " << cam.name << " pixel " << x << "," << y;
        ++ground;
      }
    EXPECT_EQ(ground, 120);
    // Sky: background depth is +inf in our format (EEVEE's 65504 is converted).
    int sky = 0;
    for (int x = 0; x < cam.width; ++x) sky += std::isinf(depth.at(x, 0)) ? 1 : 0;
    EXPECT_GT(sky, 0) << "no sky pixels in the top row of view " << cam.name;
  }
  EXPECT_GE(checked, 10);
  std::printf("markers checked: %d, mean error %.3f px, max %.3f px\n", checked, sum_err / checked, max_err);
}

}  // namespace
}  // namespace weathergs::capture
