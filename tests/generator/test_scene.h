// Clean test inputs made in C++ (no Blender): cameras on a line looking at a textured wall over a
// ground plane, with exact planar depth, and a sky background at a configurable depth value.
#pragma once

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "core/dataset.h"
#include "core/image.h"

namespace weathergs::testing {

struct SceneOptions {
  int views = 3;
  int width = 96, height = 64;
  double fx = 80;
  double exposure_s = 1.0 / 60.0;
  double time_step_s = 0.1;   // time_s of view i = i * time_step_s
  double wall_distance_m = 8;
  float background_depth = std::numeric_limits<float>::infinity();
  bool thin_lens = false;     // f/2.8, 35 mm, focused at 10 m
};

// Value noise in [0, 1) from integer lattice coordinates (deterministic texture).
inline double lattice_noise(int64_t x, int64_t y) {
  uint64_t h = uint64_t(x) * 0x9E3779B97F4A7C15ull ^ (uint64_t(y) + 0x632BE59BD9B4E019ull) * 0xC2B2AE3D27D4EB4Full;
  h ^= h >> 29;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 32;
  return double(h >> 11) / double(1ull << 53);
}

inline void make_clean_dataset(const std::string& dir, const SceneOptions& o) {
  namespace fs = std::filesystem;
  fs::create_directories(fs::path(dir) / "clean");
  fs::create_directories(fs::path(dir) / "depth");
  Dataset d;
  d.root = dir;
  d.info.name = "synthetic";
  d.info.scene = "wall";
  std::vector<std::string> names;
  for (int i = 0; i < o.views; ++i) {
    Camera c;
    char name[16];
    std::snprintf(name, sizeof(name), "%03d", i);
    c.name = name;
    c.width = o.width, c.height = o.height;
    c.fx = c.fy = o.fx;
    c.cx = o.width / 2.0, c.cy = o.height / 2.0;
    // Looking along world +y from (0.4 i, 0, 1.6): camera x = world x, y = -world z, z = world y.
    Eigen::Matrix3d r;
    r << 1, 0, 0, 0, 0, -1, 0, 1, 0;
    const Eigen::Vector3d center(0.4 * i, 0, 1.6);
    c.camera_from_world.setIdentity();
    c.camera_from_world.topLeftCorner<3, 3>() = r;
    c.camera_from_world.topRightCorner<3, 1>() = -r * center;
    c.time_s = i * o.time_step_s;
    c.exposure_s = o.exposure_s;
    if (o.thin_lens) c.f_number = 2.8, c.focal_length_mm = 35, c.focus_distance_m = 10;
    Image rgb(o.width, o.height, 3, ColorSpace::kSRGB);
    Image depth(o.width, o.height, 1, ColorSpace::kLinear);
    for (int y = 0; y < o.height; ++y)
      for (int x = 0; x < o.width; ++x) {
        const Eigen::Vector3d dir = r.transpose() * Eigen::Vector3d((x + 0.5 - c.cx) / c.fx, (y + 0.5 - c.cy) / c.fy, 1.0);
        double t = std::numeric_limits<double>::infinity();
        double col[3] = {0.62, 0.74, 0.92};  // sky
        if (dir.y() > 0) {
          const double tw = (o.wall_distance_m - center.y()) / dir.y();
          const Eigen::Vector3d p = center + tw * dir;
          if (p.z() >= 0 && p.z() <= 4) {
            t = tw;
            const double n = lattice_noise(int64_t(std::floor(p.x() * 5)), int64_t(std::floor(p.z() * 5)));
            col[0] = 0.25 + 0.5 * n, col[1] = 0.2 + 0.4 * n, col[2] = 0.15 + 0.3 * n;
          }
        }
        if (dir.z() < 0) {
          const double tg = -center.z() / dir.z();
          if (tg < t) {
            t = tg;
            const Eigen::Vector3d p = center + tg * dir;
            const double n = lattice_noise(int64_t(std::floor(p.x() * 3)) + 1000, int64_t(std::floor(p.y() * 3)));
            col[0] = col[1] = col[2] = 0.1 + 0.3 * n;
          }
        }
        for (int k = 0; k < 3; ++k) rgb.at(x, y, k) = float(col[k]);
        depth.at(x, y) = std::isfinite(t) ? float(t) : o.background_depth;  // planar: dir has z_cam = 1
      }
    write_image(d.path(ImageKind::kClean, c.name), rgb);
    write_depth(d.path(ImageKind::kDepth, c.name), depth);
    d.cameras.push_back(c);
    names.push_back(c.name);
  }
  d.info.splits = llff_splits(names);
  d.info.splits_rule = kLlffSplitRule;
  write_dataset(d);
}

}  // namespace weathergs::testing
