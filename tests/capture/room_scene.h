// A synthetic textured room corner, ray cast (so the true cameras and depth are known), and a
// camera path through it: the footage of the import tests.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

#include "core/camera.h"

namespace weathergs::capture {

inline uint32_t hash3(int x, int y, int z) {
  uint32_t h = uint32_t(x) * 73856093u ^ uint32_t(y) * 19349663u ^ uint32_t(z) * 83492791u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  return h ^ (h >> 15);
}

// Multi-octave value noise in [0, 1]: non-repeating texture with features at every scale.
inline double texture(double u, double v, int plane) {
  double sum = 0, amp = 0.5;
  for (int o = 0; o < 5; ++o) {
    const double s = 4.0 * (1 << o);
    const int iu = int(std::floor(u * s)), iv = int(std::floor(v * s));
    const double fu = u * s - iu, fv = v * s - iv;
    auto val = [&](int a, int b) { return (hash3(a, b, plane * 16 + o) & 0xffff) / 65535.0; };
    const double a = val(iu, iv) * (1 - fu) + val(iu + 1, iv) * fu;
    const double b = val(iu, iv + 1) * (1 - fu) + val(iu + 1, iv + 1) * fu;
    sum += amp * (a * (1 - fv) + b * fv);
    amp *= 0.5;
  }
  return sum / (1 - std::pow(0.5, 5));
}

// A room corner: floor z = 0, back wall y = 4, left wall x = -2, right wall x = 2.
// Renders the room (8-bit BGR); *depth (if given) receives the planar depth (+inf on background).
inline cv::Mat render_room(const Camera& cam, std::vector<float>* depth = nullptr) {
  cv::Mat img(cam.height, cam.width, CV_8UC3);
  if (depth) depth->assign(size_t(cam.width) * size_t(cam.height), std::numeric_limits<float>::infinity());
  const Eigen::Vector3d forward = cam.rotation().row(2).transpose();
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const Eigen::Vector3d o = cam.center_world();
      const Eigen::Vector3d d = cam.ray_direction_world({x + 0.5, y + 0.5});
      double best = 1e9, c = 0;
      int plane = -1;
      auto hit = [&](double t, int p, double u, double v) {
        if (t > 1e-6 && t < best) best = t, plane = p, c = texture(u, v, p);
      };
      if (d.z() < 0) { double t = -o.z() / d.z(); Eigen::Vector3d q = o + t * d; hit(t, 0, q.x(), q.y()); }
      if (d.y() > 0) { double t = (4 - o.y()) / d.y(); Eigen::Vector3d q = o + t * d; hit(t, 1, q.x(), q.z()); }
      if (d.x() < 0) { double t = (-2 - o.x()) / d.x(); Eigen::Vector3d q = o + t * d; hit(t, 2, q.y(), q.z()); }
      if (d.x() > 0) { double t = (2 - o.x()) / d.x(); Eigen::Vector3d q = o + t * d; hit(t, 3, q.y(), q.z()); }
      if (depth && plane >= 0) (*depth)[size_t(y) * size_t(cam.width) + size_t(x)] = float(best * d.dot(forward));
      const double tint[4][3] = {{0.9, 0.8, 0.6}, {0.6, 0.8, 0.9}, {0.9, 0.6, 0.6}, {0.6, 0.9, 0.6}};
      for (int ch = 0; ch < 3; ++ch)
        img.at<cv::Vec3b>(y, x)[2 - ch] = cv::saturate_cast<uint8_t>(plane < 0 ? 200 : 255 * c * tint[plane][ch]);
    }
  return img;
}

inline std::vector<Camera> room_path(int n) {
  std::vector<Camera> cams;
  for (int k = 0; k < n; ++k) {
    Camera c;
    c.name = std::to_string(k);
    c.width = 320, c.height = 240;
    c.fx = c.fy = 260, c.cx = 160, c.cy = 120;
    const Eigen::Vector3d center(-0.8 + 1.6 * k / (n - 1), -1.0 + 0.1 * std::sin(k), 1.2 + 0.15 * std::cos(0.7 * k));
    const Eigen::Vector3d target(0.0, 4.0, 0.8);
    const Eigen::Vector3d z = (target - center).normalized();
    const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d y = z.cross(x);
    Eigen::Matrix3d r;
    r.row(0) = x, r.row(1) = y, r.row(2) = z;
    c.camera_from_world.topLeftCorner<3, 3>() = r;
    c.camera_from_world.topRightCorner<3, 1>() = -r * center;
    cams.push_back(c);
  }
  return cams;
}

// The footage: one 320x240 MJPG frame per camera at 10 fps. False if OpenCV cannot write it.
inline bool write_room_video(const std::string& path, const std::vector<Camera>& cameras) {
  cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, cv::Size(320, 240));
  if (!writer.isOpened()) return false;
  for (const Camera& c : cameras) writer.write(render_room(c));
  return true;
}

}  // namespace weathergs::capture
