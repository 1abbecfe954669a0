// Shared helpers of the reconstruction tests: random Gaussian scenes, cameras looking at the origin,
// and a synthetic dataset written with core's writers from our own forward pass.
#pragma once

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/colmap_model.h"
#include <filesystem>
#include "core/dataset.h"
#include "core/image.h"
#include "core/rng.h"
#include "reconstruction/gaussians.h"
#include "reconstruction/rasterizer.h"

namespace weathergs::reconstruction::testing {

// A camera at `eye` looking at `target` with world +z up (OpenCV axes: x right, y down, z forward).
inline Camera look_at_camera(const std::string& name, int width, int height, double focal,
                             const Eigen::Vector3d& eye, const Eigen::Vector3d& target = Eigen::Vector3d::Zero()) {
  Camera c;
  c.name = name;
  c.width = width;
  c.height = height;
  c.fx = c.fy = focal;
  c.cx = width / 2.0;
  c.cy = height / 2.0;
  const Eigen::Vector3d fwd = (target - eye).normalized();
  Eigen::Vector3d up(0, 0, 1);
  if (std::abs(fwd.dot(up)) > 0.99) up = Eigen::Vector3d(0, 1, 0);
  const Eigen::Vector3d right = fwd.cross(up).normalized();
  const Eigen::Vector3d down = fwd.cross(right);
  Eigen::Matrix3d r;
  r.row(0) = right.transpose();
  r.row(1) = down.transpose();
  r.row(2) = fwd.transpose();
  c.camera_from_world.setIdentity();
  c.camera_from_world.topLeftCorner<3, 3>() = r;
  c.camera_from_world.topRightCorner<3, 1>() = -r * eye;
  return c;
}

// n Gaussians in a ball of `radius` around the origin, random anisotropic scales around `scale`,
// random rotations, opacities in (0.3, 0.9) and random colours with some view dependence.
template <typename T>
GaussianSet<T> random_gaussians(int n, uint64_t seed, double radius = 1.0, double scale = 0.08,
                                double sh_rest = 0.1) {
  GaussianSet<T> g;
  g.assign_zero(n);
  for (int i = 0; i < n; ++i) {
    Rng rng(seed, 1, i);
    Eigen::Vector3d p;
    do {
      p = Eigen::Vector3d(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    } while (p.norm() > 1);
    for (int k = 0; k < 3; ++k) {
      g.position[i * 3 + k] = T(p[k] * radius);
      g.log_scale[i * 3 + k] = T(std::log(scale) + rng.uniform(-0.5f, 0.5f));
    }
    for (int k = 0; k < 4; ++k) g.rotation[i * 4 + k] = T(rng.normal());
    g.opacity_logit[i] = T(inverse_sigmoid(rng.uniform(0.3f, 0.9f)));
    for (int c = 0; c < 3; ++c) g.sh[i * kShFloats + c] = T(rgb_to_sh0(rng.uniform(0.1f, 0.9f)));
    for (int k = 3; k < kShFloats; ++k) g.sh[i * kShFloats + k] = T(sh_rest * rng.normal());
  }
  return g;
}

// Cameras on a ring of `distance` around the origin, slightly above it.
inline std::vector<Camera> ring_cameras(int count, int width, int height, double focal, double distance) {
  std::vector<Camera> cams;
  for (int i = 0; i < count; ++i) {
    const double a = 2 * M_PI * i / count;
    char name[16];
    std::snprintf(name, sizeof name, "%03d", i);
    cams.push_back(look_at_camera(name, width, height, focal,
                                  Eigen::Vector3d(distance * std::cos(a), distance * std::sin(a), 0.3 * distance)));
  }
  return cams;
}

// Float image of a render (H x W x 3 in [0, 1], sRGB as the trainer treats images).
inline Image to_image(const std::vector<float>& rgb, int width, int height) {
  Image img(width, height, 3);
  for (size_t i = 0; i < rgb.size(); ++i) img.data[i] = std::clamp(rgb[i], 0.f, 1.f);
  return img;
}

inline Image render_image(const GaussianSet<float>& g, const Camera& cam, int sh_degree = 3) {
  RasterState<float> st;
  RasterSettings<float> rs;
  rs.sh_degree = sh_degree;
  rasterize_forward(g, RasterCamera<float>::from(cam), rs, &st);
  return to_image(st.image, cam.width, cam.height);
}

// Writes a dataset (dataset.json, cameras.json, images/<view>.png with LLFF splits) rendered from
// `truth`; with points, also sparse/0 with the true centres (jittered by `jitter_m`) as the SfM cloud.
inline Dataset write_synthetic_dataset(const std::string& root, const GaussianSet<float>& truth,
                                       const std::vector<Camera>& cameras, bool with_points,
                                       double jitter_m = 0.01, uint64_t seed = 1) {
  namespace fs = std::filesystem;
  fs::create_directories(fs::path(root) / "images");
  Dataset d;
  d.root = root;
  d.cameras = cameras;
  std::vector<std::string> names;
  for (const Camera& c : cameras) {
    names.push_back(c.name);
    write_image(d.path(ImageKind::kImages, c.name), render_image(truth, c));
  }
  d.info.name = "synthetic_clear";
  d.info.scene = "synthetic";
  d.info.splits = llff_splits(names);
  d.info.splits_rule = kLlffSplitRule;
  write_dataset(d);
  if (with_points) {
    fs::create_directories(fs::path(root) / "sparse/0");
    ColmapModel m = colmap_model_from_cameras(cameras);
    for (size_t i = 0; i < truth.size(); ++i) {
      Rng rng(seed, 77, i);
      ColmapPoint3D p;
      p.id = int64_t(i) + 1;
      for (int k = 0; k < 3; ++k) {
        p.xyz[k] = truth.position[i * 3 + k] + jitter_m * rng.normal();
        p.rgb[k] = std::round(255 * std::clamp(sh0_to_rgb(truth.sh[i * kShFloats + k]), 0.0, 1.0));
      }
      p.track = {{1, 0}, {2, 0}};
      m.points.push_back(p);
    }
    write_colmap_text((fs::path(root) / "sparse/0").string(), m);
  }
  return d;
}

// The largest blend weight alpha * T of each Gaussian over the pixels of `cam`, by a per-pixel loop
// in double written independently of the tile kernels: per pixel, every rendered Gaussian whose
// record's pixel box (the 3-sigma rectangle within the alpha extent) holds it, in (depth, index)
// order, blended front to back with the reference's cut-offs (alpha < 1/255 skipped, the blend
// stopping where the transmittance would fall below 1e-4).
inline std::vector<double> reference_max_blend_weights(const GaussianSet<double>& g, const Camera& cam) {
  RasterState<double> st;
  RasterSettings<double> rs;
  rasterize_forward(g, RasterCamera<double>::from(cam), rs, &st);
  std::vector<int> order;
  for (size_t i = 0; i < g.size(); ++i)
    if (st.radius[i] > 0) order.push_back(int(i));
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    return float(st.depth[a]) != float(st.depth[b]) ? float(st.depth[a]) < float(st.depth[b]) : a < b;
  });
  std::vector<double> best(g.size(), 0.0);
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      double trans = 1;
      for (int i : order) {
        const double* sp = &st.splat[size_t(i) * kSplatFloats];
        if (x < sp[12] || x > sp[13] || y < sp[14] || y > sp[15]) continue;
        const double dx = st.mean2d[i * 2] - (x + 0.5), dy = st.mean2d[i * 2 + 1] - (y + 0.5);
        const double power =
            -0.5 * (st.conic[i * 3] * dx * dx + st.conic[i * 3 + 2] * dy * dy) - st.conic[i * 3 + 1] * dx * dy;
        if (power > 0) continue;
        const double alpha = std::min(0.99, st.opacity[i] * std::exp(power));
        if (alpha < 1.0 / 255) continue;
        if (trans * (1 - alpha) < 1e-4) break;
        best[i] = std::max(best[i], alpha * trans);
        trans *= 1 - alpha;
      }
    }
  return best;
}

// Mean PSNR over the dataset's test views of the renders `renders_dir/<view>.png` (8-bit, as
// `weathergs render` writes them) against the dataset's images.
inline double mean_test_psnr(const Dataset& d, const std::string& renders_dir) {
  double sum = 0;
  for (const std::string& v : d.split("test")) {
    const Image a = read_image(renders_dir + "/" + v + ".png"), b = read_image(d.path(ImageKind::kImages, v));
    double se = 0;
    for (size_t i = 0; i < a.data.size(); ++i) se += (a.data[i] - b.data[i]) * (a.data[i] - b.data[i]);
    sum += 10 * std::log10(1.0 / std::max(se / double(a.data.size()), 1e-12));
  }
  return sum / double(d.split("test").size());
}

}  // namespace weathergs::reconstruction::testing
