#include "core/colmap_model.h"

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"

namespace weathergs {

namespace fs = std::filesystem;

Eigen::Vector4d rotation_to_quaternion_wxyz(const Eigen::Matrix3d& r) {
  Eigen::Quaterniond q(r);
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1;  // canonical sign, as COLMAP writes
  return {q.w(), q.x(), q.y(), q.z()};
}

Eigen::Matrix3d quaternion_wxyz_to_rotation(const Eigen::Vector4d& q) {
  return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
}

namespace {
// Iterates over non-comment, non-empty lines... except images.txt, whose second line per image may be
// empty (no 2D points); that reader handles lines itself.
std::vector<std::pair<int, std::string>> read_lines(const std::string& path, bool keep_empty) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open file (missing or unreadable)");
  std::vector<std::pair<int, std::string>> lines;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!line.empty() && line[0] == '#') continue;
    if (line.empty() && !keep_empty) continue;
    lines.emplace_back(n, line);
  }
  return lines;
}

[[noreturn]] void bad_line(const std::string& path, int line, const std::string& what) {
  throw InputError(path + ":" + std::to_string(line), what);
}
}  // namespace

std::vector<ColmapPoint3D> read_colmap_points3d(const std::string& path) {
  std::vector<ColmapPoint3D> points;
  for (const auto& [n, line] : read_lines(path, false)) {
    std::istringstream s(line);
    ColmapPoint3D p;
    if (!(s >> p.id >> p.xyz.x() >> p.xyz.y() >> p.xyz.z() >> p.rgb.x() >> p.rgb.y() >> p.rgb.z() >> p.error))
      bad_line(path, n, "expected POINT3D_ID X Y Z R G B ERROR TRACK[]");
    int image_id, idx;
    while (s >> image_id >> idx) p.track.emplace_back(image_id, idx);
    if (!p.xyz.allFinite()) bad_line(path, n, "non-finite point coordinates");
    points.push_back(std::move(p));
  }
  return points;
}

ColmapModel read_colmap_text(const std::string& dir) {
  ColmapModel m;
  const std::string cams = (fs::path(dir) / "cameras.txt").string();
  for (const auto& [n, line] : read_lines(cams, false)) {
    std::istringstream s(line);
    ColmapCameraModel c;
    std::string model;
    if (!(s >> c.id >> model >> c.width >> c.height)) bad_line(cams, n, "expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]");
    if (model == "PINHOLE") {
      if (!(s >> c.fx >> c.fy >> c.cx >> c.cy)) bad_line(cams, n, "PINHOLE expects fx fy cx cy");
    } else if (model == "SIMPLE_PINHOLE") {
      if (!(s >> c.fx >> c.cx >> c.cy)) bad_line(cams, n, "SIMPLE_PINHOLE expects f cx cy");
      c.fy = c.fx;
    } else {
      bad_line(cams, n, "unsupported camera model " + model + " (expected PINHOLE or SIMPLE_PINHOLE)");
    }
    m.cameras.push_back(c);
  }
  const std::string imgs = (fs::path(dir) / "images.txt").string();
  auto lines = read_lines(imgs, true);
  // Drop trailing empty lines, then read pairs: the pose line and the (possibly empty) points line.
  size_t i = 0;
  while (i < lines.size()) {
    if (lines[i].second.empty()) { ++i; continue; }
    const auto& [n, line] = lines[i];
    std::istringstream s(line);
    ColmapImage im;
    Eigen::Vector4d q;
    Eigen::Vector3d t;
    if (!(s >> im.id >> q[0] >> q[1] >> q[2] >> q[3] >> t.x() >> t.y() >> t.z() >> im.camera_id >> im.name))
      bad_line(imgs, n, "expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME");
    im.camera_from_world.topLeftCorner<3, 3>() = quaternion_wxyz_to_rotation(q);
    im.camera_from_world.topRightCorner<3, 1>() = t;
    if (i + 1 < lines.size()) {
      std::istringstream p(lines[i + 1].second);
      double x, y, id;
      while (p >> x >> y >> id) im.points2d.emplace_back(x, y, id);
    }
    m.images.push_back(std::move(im));
    i += 2;
  }
  m.points = read_colmap_points3d((fs::path(dir) / "points3D.txt").string());
  return m;
}

void write_colmap_text(const std::string& dir, const ColmapModel& m) {
  std::ostringstream c;
  c << std::setprecision(17);
  c << "# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n";
  c << "# Number of cameras: " << m.cameras.size() << "\n";
  for (const auto& cam : m.cameras)
    c << cam.id << " PINHOLE " << cam.width << " " << cam.height << " " << cam.fx << " " << cam.fy << " "
      << cam.cx << " " << cam.cy << "\n";
  std::ostringstream im;
  im << std::setprecision(17);
  im << "# Image list with two lines of data per image:\n"
        "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n#   POINTS2D[] as (X, Y, POINT3D_ID)\n";
  im << "# Number of images: " << m.images.size() << "\n";
  for (const auto& img : m.images) {
    Eigen::Vector4d q = rotation_to_quaternion_wxyz(img.camera_from_world.topLeftCorner<3, 3>());
    Eigen::Vector3d t = img.camera_from_world.topRightCorner<3, 1>();
    im << img.id << " " << q[0] << " " << q[1] << " " << q[2] << " " << q[3] << " " << t.x() << " " << t.y()
       << " " << t.z() << " " << img.camera_id << " " << img.name << "\n";
    for (size_t k = 0; k < img.points2d.size(); ++k)
      im << (k ? " " : "") << img.points2d[k].x() << " " << img.points2d[k].y() << " " << int64_t(img.points2d[k].z());
    im << "\n";
  }
  std::ostringstream p;
  p << std::setprecision(17);
  p << "# 3D point list with one line of data per point:\n"
       "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n";
  p << "# Number of points: " << m.points.size() << "\n";
  for (const auto& pt : m.points) {
    p << pt.id << " " << pt.xyz.x() << " " << pt.xyz.y() << " " << pt.xyz.z() << " " << int(pt.rgb.x()) << " "
      << int(pt.rgb.y()) << " " << int(pt.rgb.z()) << " " << pt.error;
    for (const auto& [iid, idx] : pt.track) p << " " << iid << " " << idx;
    p << "\n";
  }
  write_file_atomic((fs::path(dir) / "cameras.txt").string(), c.str());
  write_file_atomic((fs::path(dir) / "images.txt").string(), im.str());
  write_file_atomic((fs::path(dir) / "points3D.txt").string(), p.str());
}

ColmapModel colmap_model_from_cameras(const std::vector<Camera>& cameras, const std::string& ext) {
  ColmapModel m;
  int id = 1;
  for (const Camera& cam : cameras) {
    m.cameras.push_back({id, cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy});
    ColmapImage img;
    img.id = id;
    img.camera_id = id;
    img.name = cam.name + ext;
    img.camera_from_world = cam.camera_from_world;
    m.images.push_back(img);
    ++id;
  }
  return m;
}

}  // namespace weathergs
