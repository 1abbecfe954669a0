// render_depth: planar depth of a trained model (render --depth), used to weather any capture.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "reconstruction/run.h"
#include "tests/reconstruction/test_scene.h"

namespace weathergs::reconstruction {
namespace {

// An opaque wall of small isotropic Gaussians on the plane x = wall_x, facing a camera on the -x side.
GaussianSet<float> wall(double wall_x, double half_size, double spacing) {
  GaussianSet<float> g;
  for (double y = -half_size; y <= half_size + 1e-9; y += spacing)
    for (double z = -half_size; z <= half_size + 1e-9; z += spacing) {
      for (double v : {wall_x, y, z}) g.position.push_back(float(v));
      for (int k = 0; k < 3; ++k) g.log_scale.push_back(float(std::log(spacing)));
      for (double v : {1.0, 0.0, 0.0, 0.0}) g.rotation.push_back(float(v));
      g.opacity_logit.push_back(float(inverse_sigmoid(0.99)));
      for (int k = 0; k < 48; ++k) g.sh.push_back(0.f);
    }
  return g;
}

TEST(RenderDepth, PlanarDepthOfAWallAndBackgroundOutside) {
  const Camera cam = testing::look_at_camera("v", 64, 48, 60, Eigen::Vector3d(-4, 0, 0), Eigen::Vector3d(0, 0, 0));
  // A wall 4 m ahead covering the middle of the view, nothing elsewhere.
  const std::vector<float> d = render_depth(wall(0.0, 1.0, 0.05), cam, 0.5);
  ASSERT_EQ(d.size(), size_t(64 * 48));
  // The wall spans +-1 m at 4 m: +-15 px around the centre. Inside: depth 4 m (the Gaussians' own
  // depth spread is their 5 cm size: the blend of a few of them at the same z).
  const double kDepthTolM = 1e-3;  // float blending of identical depths
  int inside = 0, outside_inf = 0, outside = 0;
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      const float z = d[size_t(y) * 64 + size_t(x)];
      ASSERT_FALSE(std::isnan(z));
      if (std::abs(x + 0.5 - 32) < 12 && std::abs(y + 0.5 - 24) < 12) {
        EXPECT_NEAR(z, 4.0, kDepthTolM) << x << "," << y;
        ++inside;
      } else if (std::abs(x + 0.5 - 32) > 20 || std::abs(y + 0.5 - 24) > 20) {
        ++outside;
        outside_inf += std::isinf(z) ? 1 : 0;
      }
    }
  EXPECT_GT(inside, 400);
  EXPECT_EQ(outside_inf, outside);
  // A second wall behind the first changes nothing where the first is opaque; seen alone, it is at 6 m.
  GaussianSet<float> two = wall(0.0, 1.0, 0.05);
  const GaussianSet<float> back = wall(2.0, 3.0, 0.05);
  for (auto [dst, src] : {std::pair{&two.position, &back.position}, {&two.log_scale, &back.log_scale},
                          {&two.rotation, &back.rotation}, {&two.opacity_logit, &back.opacity_logit},
                          {&two.sh, &back.sh}})
    dst->insert(dst->end(), src->begin(), src->end());
  const std::vector<float> d2 = render_depth(two, cam, 0.5);
  EXPECT_NEAR(d2[size_t(24) * 64 + 32], 4.0, 0.01);
  EXPECT_NEAR(d2[size_t(2) * 64 + 2], 6.0, 0.01);
  // Empty model: all background, no NaN.
  for (float z : render_depth(GaussianSet<float>{}, cam, 0.5)) ASSERT_TRUE(std::isinf(z));
}

}  // namespace
}  // namespace weathergs::reconstruction
