#include "reconstruction/distractors.h"

#include <algorithm>
#include <cmath>

#include "core/constants.h"
#include "core/error.h"
#include "core/rng.h"

namespace weathergs::reconstruction {
namespace {

constexpr uint64_t kStreamDistractors = 0x6469737472ull;  // "distr": placement of view v's distractors

// Median depth of the scene's Gaussians that project into the camera's image (0 if none).
double scene_depth(const Camera& cam, const GaussianSet<float>& g, const std::vector<int32_t>& owner) {
  std::vector<double> depths;
  for (size_t i = 0; i < g.size(); ++i) {
    if (owner[i] != kSceneOwner) continue;
    const Eigen::Vector3d p(g.position[i * 3], g.position[i * 3 + 1], g.position[i * 3 + 2]);
    const Eigen::Vector3d pc = (cam.camera_from_world * p.homogeneous()).head<3>();
    if (!(pc.z() > 0.2)) continue;
    const double u = cam.fx * pc.x() / pc.z() + cam.cx, v = cam.fy * pc.y() / pc.z() + cam.cy;
    if (u >= 0 && v >= 0 && u < cam.width && v < cam.height) depths.push_back(pc.z());
  }
  if (depths.empty()) return 0;
  auto mid = depths.begin() + ptrdiff_t(depths.size() / 2);
  std::nth_element(depths.begin(), mid, depths.end());
  return *mid;
}

}  // namespace

void add_distractors(const std::vector<Camera>& cameras, int per_view, uint64_t seed,
                     const DistractorPlacement& placement, GaussianSet<float>* g, std::vector<int32_t>* owner) {
  WGS_CHECK(per_view >= 0);
  WGS_CHECK_EQ(owner->size(), g->size());
  if (per_view == 0) return;
  const size_t first = g->size();
  // Scene depths from the scene as given (before any distractor is added).
  std::vector<double> depth(cameras.size());
  for (size_t v = 0; v < cameras.size(); ++v) depth[v] = scene_depth(cameras[v], *g, *owner);
  g->resize(first + cameras.size() * size_t(per_view));
  owner->resize(g->size(), kSceneOwner);
  const float logit = float(inverse_sigmoid(placement.initial_opacity));
  for (size_t v = 0; v < cameras.size(); ++v) {
    const Camera& cam = cameras[v];
    // No scene point in view: 10 m, a street-scale guess; only the depth range depends on it.
    const double d = depth[v] > 0 ? depth[v] : 10.0;
    const double near = std::max(placement.near_m, placement.near_fraction * d);
    const double far = std::max(near * 1.5, placement.far_fraction * d);
    // Footprint radius (px) so that per_view discs cover the image once.
    const double radius_px = std::sqrt(double(cam.width) * cam.height / (kPi * per_view));
    const Eigen::Matrix4d world_from_camera = cam.world_from_camera();
    for (int k = 0; k < per_view; ++k) {
      const size_t i = first + v * size_t(per_view) + size_t(k);
      Rng rng(seed, kStreamDistractors ^ (uint64_t(v) << 24), uint64_t(k));
      const double u = rng.uniform() * cam.width, w = rng.uniform() * cam.height;
      const double inv = 1.0 / far + rng.uniform() * (1.0 / near - 1.0 / far);
      const double z = 1.0 / inv;
      const Eigen::Vector3d pc((u - cam.cx) * z / cam.fx, (w - cam.cy) * z / cam.fy, z);
      const Eigen::Vector3d pw = (world_from_camera * pc.homogeneous()).head<3>();
      for (int c = 0; c < 3; ++c) g->position[i * 3 + c] = float(pw[c]);
      const float log_scale = float(std::log(radius_px * z / cam.fx));
      for (int c = 0; c < 3; ++c) g->log_scale[i * 3 + c] = log_scale;
      g->rotation[i * 4] = 1.f;  // identity; the other three stay 0
      g->opacity_logit[i] = logit;
      // sh stays 0: SH DC 0 is mid grey (rgb 0.5)
      (*owner)[i] = int32_t(v);
    }
  }
}

void rows_for_view(const std::vector<int32_t>& owner, int view, std::vector<int64_t>* rows) {
  rows->clear();
  for (size_t i = 0; i < owner.size(); ++i)
    if (owner[i] == kSceneOwner || owner[i] == view) rows->push_back(int64_t(i));
}

void gather_rows(const GaussianSet<float>& g, const std::vector<int64_t>& rows, GaussianSet<float>* sub) {
  sub->resize(rows.size());
  for (size_t k = 0; k < rows.size(); ++k) sub->copy_from(g, size_t(rows[k]), k);
}

void scatter_rows(const GaussianSet<float>& sub, const std::vector<int64_t>& rows, size_t n, GaussianSet<float>* full) {
  WGS_CHECK_EQ(sub.size(), rows.size());
  full->assign_zero(n);
  for (size_t k = 0; k < rows.size(); ++k) full->copy_from(sub, k, size_t(rows[k]));
}

GaussianSet<float> scene_rows(const GaussianSet<float>& g, const std::vector<int32_t>& owner) {
  WGS_CHECK_EQ(owner.size(), g.size());
  GaussianSet<float> out = g;
  std::vector<char> keep(owner.size());
  for (size_t i = 0; i < owner.size(); ++i) keep[i] = owner[i] == kSceneOwner;
  out.keep(keep);
  return out;
}

}  // namespace weathergs::reconstruction
