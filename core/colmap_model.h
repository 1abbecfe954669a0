// COLMAP text model (cameras.txt, images.txt, points3D.txt) as used by sparse/0 in a dataset.
// Only PINHOLE cameras are written; PINHOLE and SIMPLE_PINHOLE are read. COLMAP stores world-to-
// camera poses as a quaternion (qw qx qy qz) and translation in OpenCV axes, i.e. exactly our
// camera_from_world, and uses the same pixel-corner origin.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/camera.h"

namespace weathergs {

struct ColmapPoint3D {
  int64_t id = 0;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();
  Eigen::Vector3d rgb = Eigen::Vector3d::Zero();  // sRGB in [0, 255]
  double error = 0;
  std::vector<std::pair<int, int>> track;  // (image_id, point2D_idx)
};

struct ColmapImage {
  int id = 0;
  int camera_id = 0;
  std::string name;  // file name, e.g. "007.png"
  Eigen::Matrix4d camera_from_world = Eigen::Matrix4d::Identity();
  std::vector<Eigen::Vector3d> points2d;  // (x, y, point3D_id or -1)
};

struct ColmapCameraModel {
  int id = 0;
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
};

struct ColmapModel {
  std::vector<ColmapCameraModel> cameras;
  std::vector<ColmapImage> images;
  std::vector<ColmapPoint3D> points;
};

// Reads "<dir>/cameras.txt", "<dir>/images.txt", "<dir>/points3D.txt". InputError with file:line.
ColmapModel read_colmap_text(const std::string& dir);
// Reads only points3D.txt (e.g. for initializing Gaussians).
std::vector<ColmapPoint3D> read_colmap_points3d(const std::string& path);
// Writes the three files atomically into dir (which must exist).
void write_colmap_text(const std::string& dir, const ColmapModel& model);
// A model with one PINHOLE camera per view, image ids 1..N in the given order, and no points:
// the input of `colmap point_triangulator` with known poses.
ColmapModel colmap_model_from_cameras(const std::vector<Camera>& cameras, const std::string& image_ext = ".png");

Eigen::Vector4d rotation_to_quaternion_wxyz(const Eigen::Matrix3d& r);
Eigen::Matrix3d quaternion_wxyz_to_rotation(const Eigen::Vector4d& q);

}  // namespace weathergs
