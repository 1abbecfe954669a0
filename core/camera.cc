#include "core/camera.h"

#include <cmath>
#include <sstream>

#include "core/error.h"

namespace weathergs {

Eigen::Matrix4d Camera::world_from_camera() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  const Eigen::Matrix3d r = rotation();
  m.topLeftCorner<3, 3>() = r.transpose();
  m.topRightCorner<3, 1>() = -r.transpose() * translation();
  return m;
}

Eigen::Vector3d Camera::center_world() const { return -rotation().transpose() * translation(); }

Eigen::Vector3d Camera::to_camera(const Eigen::Vector3d& p_world) const {
  return rotation() * p_world + translation();
}

Eigen::Vector2d Camera::project_camera(const Eigen::Vector3d& p) const {
  return {fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy};
}

std::optional<Eigen::Vector2d> Camera::project(const Eigen::Vector3d& p_world) const {
  Eigen::Vector3d p = to_camera(p_world);
  if (!(p.z() > 0)) return std::nullopt;
  return project_camera(p);
}

Eigen::Vector3d Camera::unproject(const Eigen::Vector2d& uv, double z) const {
  Eigen::Vector3d p_camera((uv.x() - cx) / fx * z, (uv.y() - cy) / fy * z, z);
  return rotation().transpose() * (p_camera - translation());
}

Eigen::Vector3d Camera::ray_direction_world(const Eigen::Vector2d& uv) const {
  Eigen::Vector3d d((uv.x() - cx) / fx, (uv.y() - cy) / fy, 1.0);
  return (rotation().transpose() * d).normalized();
}

std::string Camera::to_string() const {
  std::ostringstream s;
  s << "Camera '" << name << "' " << width << "x" << height << " f=(" << fx << ", " << fy << ") c=("
    << cx << ", " << cy << ") center=(" << center_world().transpose() << ") t=" << time_s
    << " exposure=" << exposure_s;
  return s.str();
}

void validate_camera(const Camera& c, const std::string& where) {
  auto bad = [&](const std::string& what) { throw InputError(where, what); };
  if (c.width <= 0 || c.height <= 0)
    bad("width and height must be positive, got " + std::to_string(c.width) + "x" + std::to_string(c.height));
  for (double v : {c.fx, c.fy})
    if (!(std::isfinite(v) && v > 0)) bad("fx and fy must be finite and positive");
  if (!std::isfinite(c.cx) || !std::isfinite(c.cy)) bad("cx and cy must be finite");
  if (!c.camera_from_world.allFinite()) bad("camera_from_world has non-finite entries");
  if ((c.camera_from_world.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-9)
    bad("camera_from_world bottom row must be [0, 0, 0, 1]");
  const Eigen::Matrix3d r = c.rotation();
  if ((r * r.transpose() - Eigen::Matrix3d::Identity()).norm() > 1e-4 || r.determinant() < 0)
    bad("camera_from_world rotation block must be orthonormal with determinant +1");
  if (!(std::isfinite(c.exposure_s) && c.exposure_s >= 0)) bad("exposure_s must be >= 0");
  if (!std::isfinite(c.time_s)) bad("time_s must be finite");
  if (c.f_number && !(*c.f_number > 0)) bad("f_number must be positive");
  if (c.focal_length_mm && !(*c.focal_length_mm > 0)) bad("focal_length_mm must be positive");
  if (c.focus_distance_m && !(*c.focus_distance_m > 0)) bad("focus_distance_m must be positive");
}

}  // namespace weathergs
