// The space the radiance field lives in. Our benchmark captures are forward-facing (every camera looks
// roughly the same way, the scene runs out to the horizon), where a Euclidean voxel grid wastes its
// cells on nearby empty space and cannot hold the far background. So, as NeRF does for LLFF scenes
// with normalized device coordinates, the grid is aligned with a reference camera and spans
//   u = X/Z, v = Y/Z (the image plane) and w = 1/Z (disparity, from 1/near down to 0 = infinity),
// with (X, Y, Z) a point in the reference frame. Straight rays of every view are sampled at equal
// steps of w, so near space gets fine steps and the horizon is one slice.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/camera.h"
#include "core/colmap_model.h"
#include "core/json_reader.h"

namespace weathergs::nerf {

struct FrustumFrame {
  Eigen::Matrix3d ref_from_world = Eigen::Matrix3d::Identity();  // rows: the reference x, y, z axes
  Eigen::Vector3d center = Eigen::Vector3d::Zero();              // reference camera centre (world)
  double u0 = -1, u1 = 1, v0 = -1, v1 = 1;  // image-plane bounds of the grid (X/Z, Y/Z)
  double w_max = 1;                         // 1 / near; w in [0, w_max]

  Eigen::Vector3d to_ref(const Eigen::Vector3d& p_world) const { return ref_from_world * (p_world - center); }
  Json to_json() const;
  static FrustumFrame from_json(const JsonReader& r);
};

// The reference frame of a forward-facing capture: centre = mean camera centre, z = mean viewing
// direction, x from the mean camera x axis; u/v bounds cover every camera's image at every depth
// beyond `near_m` (plus a 4% margin). InputError when the capture is not forward-facing (a camera
// looks more than 75 degrees away from the mean direction, or sees points behind the reference
// plane), naming the camera. `cameras` must not be empty.
FrustumFrame forward_facing_frame(const std::vector<Camera>& cameras, double near_m);

// The fewest SfM points a near plane is taken from (near_from_points, near_plane_points).
inline constexpr size_t kNearMinPoints = 10;
// The near plane from SfM points (world): half their 1st-percentile depth in the reference frame of
// `cameras` (cameras sit up to ~1 m before or behind the reference plane on our captures, and SfM
// rarely has points on the nearest ground), at least `min_near_m`. Returns `fallback_m` when there
// are fewer than kNearMinPoints points in front.
double near_from_points(const std::vector<Camera>& cameras, const std::vector<Eigen::Vector3d>& points,
                        double min_near_m, double fallback_m);

// The SfM points the near plane is taken from: those seen by at least kNearMinTrack views, or all of
// them when fewer than kNearMinPoints are. A point triangulated from two views has no third view to check it, and
// the 1st percentile of a small model is its second-nearest point: on the quick suite two
// whitish two-view points of pool_snow's 148 (probably falling snow matched across two views) lay
// 0.1-0.9 m in front of a camera whose median point lies at 13 m, and put the near plane ~10x closer
// than on pool_rain: a 10x larger lattice, and `nerf` 4.9 dB below what it scores with this filter
// (docs/nerf.md, "The near plane").
inline constexpr size_t kNearMinTrack = 3;
std::vector<Eigen::Vector3d> near_plane_points(const std::vector<ColmapPoint3D>& points);

}  // namespace weathergs::nerf
