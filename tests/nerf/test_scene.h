// Shared helpers of the radiance-field tests: a toy forward-facing capture of a textured plane.
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "nerf/field.h"
#include "nerf/frustum.h"
#include "nerf/trainer.h"

namespace weathergs::nerf::testing {

// Three cameras looking down world +z at a textured plane at z = 3 (the sky beyond is flat blue).
inline std::vector<TrainView> plane_views(int w = 32, int h = 24) {
  std::vector<TrainView> views;
  for (int i = 0; i < 3; ++i) {
    TrainView v;
    Camera& c = v.camera;
    c.name = "v" + std::to_string(i);
    c.width = w, c.height = h;
    c.fx = c.fy = 26;
    c.cx = w / 2.0, c.cy = h / 2.0;
    c.camera_from_world.setIdentity();
    c.camera_from_world(0, 3) = -0.25 * (i - 1);
    v.rgb.resize(size_t(w) * h * 3);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const Ray r = pixel_ray(c, x, y);
        const Eigen::Vector3d p = r.origin + (3.0 / r.direction.z()) * r.direction;
        const bool on_plane = std::abs(p.x()) < 1.2 && std::abs(p.y()) < 0.9;
        const float col[3] = {on_plane ? float(0.5 + 0.4 * std::sin(4 * p.x())) : 0.2f,
                              on_plane ? float(0.5 + 0.4 * std::cos(5 * p.y())) : 0.4f, on_plane ? 0.3f : 0.9f};
        for (int ch = 0; ch < 3; ++ch) v.rgb[(size_t(y) * w + x) * 3 + ch] = col[ch];
      }
    views.push_back(std::move(v));
  }
  return views;
}

inline std::vector<Camera> cams(const std::vector<TrainView>& views) {
  std::vector<Camera> c;
  for (const TrainView& v : views) c.push_back(v.camera);
  return c;
}

}  // namespace weathergs::nerf::testing
