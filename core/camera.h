// Pinhole camera in OpenCV axes (x right, y down, z forward), docs/formats.md conventions:
// pixel origin at the top-left corner of the top-left pixel (pixel (i, j) has its center at
// (i + 0.5, j + 0.5), as in COLMAP); u = fx * x/z + cx, v = fy * y/z + cy.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <string>

namespace weathergs {

struct Camera {
  std::string name;
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  Eigen::Matrix4d camera_from_world = Eigen::Matrix4d::Identity();  // rigid
  double time_s = 0;       // shutter opens
  double exposure_s = 0;   // shutter open for [time_s, time_s + exposure_s]
  // Optional thin-lens parameters (defocus).
  std::optional<double> f_number, focal_length_mm, focus_distance_m;

  Eigen::Matrix3d rotation() const { return camera_from_world.topLeftCorner<3, 3>(); }
  Eigen::Vector3d translation() const { return camera_from_world.topRightCorner<3, 1>(); }
  Eigen::Matrix4d world_from_camera() const;
  Eigen::Vector3d center_world() const;  // camera center C = -R^T t

  Eigen::Vector3d to_camera(const Eigen::Vector3d& p_world) const;
  // Pixel coordinates of a camera-space point; meaningless for z <= 0 (caller checks).
  Eigen::Vector2d project_camera(const Eigen::Vector3d& p_camera) const;
  // Projects a world point; returns nullopt if it is behind or on the camera plane.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& p_world) const;
  // World point at planar depth z (camera z) seen at pixel coordinates (u, v).
  Eigen::Vector3d unproject(const Eigen::Vector2d& uv, double depth_z) const;
  // Unit ray direction in world space through pixel coordinates (u, v).
  Eigen::Vector3d ray_direction_world(const Eigen::Vector2d& uv) const;

  std::string to_string() const;
};

// Throws InputError(where, ...) unless the camera is valid: positive size and focal lengths, finite
// values, a rotation block that is orthonormal with det +1 (tolerance 1e-4), bottom row 0 0 0 1,
// exposure >= 0.
void validate_camera(const Camera& camera, const std::string& where);

}  // namespace weathergs
