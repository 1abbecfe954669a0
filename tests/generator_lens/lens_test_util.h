// Small fixtures shared by the lens-droplet tests: a camera, a textured linear image, a scene with
// hand-placed drops.
#pragma once

#include <cmath>
#include <memory>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "generator/lens/drop_scene.h"
#include "generator/lens/drops.h"

namespace weathergs::generator::lens::testing {

inline Camera test_camera(int w = 160, int h = 120, double f = 140, const std::string& name = "000") {
  Camera c;
  c.name = name;
  c.width = w;
  c.height = h;
  c.fx = c.fy = f;
  c.cx = w / 2.0;
  c.cy = h / 2.0;
  return c;
}

// A smooth, non-symmetric pattern in [0.05, 0.95]: each pixel is distinguishable from its mirror.
inline Image test_image(int w, int h) {
  Image img(w, h, 3, ColorSpace::kLinear);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double u = (x + 0.5) / w, v = (y + 0.5) / h;
      img.at(x, y, 0) = float(0.05 + 0.9 * u);
      img.at(x, y, 1) = float(0.05 + 0.9 * v);
      img.at(x, y, 2) = float(0.5 + 0.45 * std::sin(9 * u + 4 * v * v));
    }
  return img;
}

constexpr double kDeg = 3.14159265358979323846 / 180;

// The lens glass at `glass_m` on the optical axis; water on the scene side unless `camera_side`.
inline GlassPlane test_plane(double glass_m = 0.03, bool camera_side = false) {
  GlassPlane p;
  p.point = Eigen::Vector3d(0, 0, glass_m);
  p.water_normal = camera_side ? Eigen::Vector3d(0, 0, -1) : Eigen::Vector3d(0, 0, 1);
  return p;
}

inline PlacedDrop test_drop(int id, const GlassPlane& plane, double x_m, double y_m, double outline_m,
                            double contact_deg) {
  return make_placed_drop(id, plane.point + Eigen::Vector3d(x_m, y_m, 0), plane.water_normal, outline_m,
                          contact_deg * kDeg);
}

}  // namespace weathergs::generator::lens::testing
