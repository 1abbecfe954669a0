#include "capture/photo_scene.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/atomic_file.h"
#include "core/constants.h"
#include "core/dataset.h"
#include "core/dataset_identity.h"
#include "core/error.h"
#include "core/sha256.h"

namespace weathergs::capture {

namespace fs = std::filesystem;

namespace {

void require_positive(double v, const char* name) {
  if (!(std::isfinite(v) && v > 0)) throw InputError("photo-scene options", std::string(name) + " must be a finite number > 0, got " + std::to_string(v));
}

// A level camera at `center` turned by `yaw` about world +z (yaw 0 looks along world +y); OpenCV axes.
Eigen::Matrix4d level_camera_from_world(double yaw, const Eigen::Vector3d& center) {
  const Eigen::Vector3d right(std::cos(yaw), -std::sin(yaw), 0), down(0, 0, -1), forward(std::sin(yaw), std::cos(yaw), 0);
  Eigen::Matrix3d r;
  r.row(0) = right;
  r.row(1) = down;
  r.row(2) = forward;
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = r;
  m.topRightCorner<3, 1>() = -r * center;
  return m;
}

}  // namespace

void PhotoSceneOptions::validate() const {
  if (photo.empty()) throw InputError("photo-scene options", "photo is required");
  if (!fs::is_regular_file(photo)) throw InputError(photo, "photograph not found");
  if (views < 3 || views > 10000) throw InputError("photo-scene options", "views must be 3..10000, got " + std::to_string(views));
  if (width < 16 || height < 16 || width > kMaxImageSide || height > kMaxImageSide)
    throw InputError("photo-scene options", "the view size must be at least 16x16 pixels, got " + std::to_string(width) + "x" + std::to_string(height));
  if (!(std::isfinite(zoom) && zoom >= 1 && zoom <= 16)) throw InputError("photo-scene options", "zoom must be in [1, 16], got " + std::to_string(zoom));
  require_positive(sensor_width_mm, "sensor_width_mm");
  require_positive(focal_length_mm, "focal_length_mm");
  require_positive(f_number, "f_number");
  require_positive(camera_height_m, "camera_height_m");
  require_positive(backdrop_m, "backdrop_m");
  require_positive(frame_interval_s, "frame_interval_s");
  if (!(std::isfinite(exposure_s) && exposure_s >= 0)) throw InputError("photo-scene options", "exposure_s must be >= 0");
  if (!(std::isfinite(focus_distance_m) && focus_distance_m > focal_length_mm * 1e-3))
    throw InputError("photo-scene options", "focus_distance_m must lie beyond the focal length, got " + std::to_string(focus_distance_m));
  if (!name.empty() && !is_safe_view_name(name)) throw InputError("photo-scene options", "name \"" + name + "\" must be made of [A-Za-z0-9._-]");
}

PhotoSceneSummary make_photo_scene(const PhotoSceneOptions& o, const std::string& out_dir) {
  o.validate();
  const cv::Mat photo = cv::imread(o.photo, cv::IMREAD_COLOR);
  if (photo.empty()) throw InputError(o.photo, "cannot decode the photograph (png, jpg, tif as OpenCV reads them)");
  const int rh = int(std::lround(o.zoom * o.height));
  const int rw = int(std::lround(double(photo.cols) * rh / photo.rows));
  if (rw < o.width)
    throw InputError(o.photo, "is " + std::to_string(photo.cols) + "x" + std::to_string(photo.rows) + ": at zoom " +
                                  std::to_string(o.zoom) + " it is " + std::to_string(rw) + " px wide, narrower than one " +
                                  std::to_string(o.width) + " px view (use a wider photograph or a larger zoom)");
  cv::Mat resized;
  cv::resize(photo, resized, cv::Size(rw, rh), 0, 0, cv::INTER_AREA);

  const double fx = o.focal_length_mm / o.sensor_width_mm * o.width;
  const double cx = o.width / 2.0, cy = o.height / 2.0;
  const int top = (rh - o.height) / 2;
  const Eigen::Vector3d center(0, 0, o.camera_height_m);

  // Planar depth is the same for every column and every view (a level camera over flat ground).
  Image depth(o.width, o.height, 1, ColorSpace::kLinear);
  for (int v = 0; v < o.height; ++v) {
    const double below = v + 0.5 - cy;
    const float z = float(below > 0 ? std::min(o.backdrop_m, o.camera_height_m * fx / below) : o.backdrop_m);
    for (int u = 0; u < o.width; ++u) depth.at(u, v, 0) = z;
  }

  AtomicDirectory out(out_dir);
  Dataset ds;
  ds.root = out.path();
  fs::create_directories(ds.dir(ImageKind::kImages));
  fs::create_directories(ds.dir(ImageKind::kDepth));
  std::vector<std::string> names;
  PhotoSceneSummary summary;
  double first_yaw = 0, last_yaw = 0;
  for (int i = 0; i < o.views; ++i) {
    // Crops spread evenly over the resized width; the view's yaw puts its centre column where the
    // crop's centre lies on the photograph seen as a plane at focal distance (exact at that column).
    const int x = int(std::lround(double(i) * (rw - o.width) / (o.views - 1)));
    const double yaw = std::atan((x + o.width / 2.0 - rw / 2.0) / fx);
    if (i == 0) first_yaw = yaw;
    last_yaw = yaw;
    Camera c;
    c.name = numbered_view_name(i);
    c.width = o.width;
    c.height = o.height;
    c.fx = c.fy = fx;
    c.cx = cx;
    c.cy = cy;
    c.camera_from_world = level_camera_from_world(yaw, center);
    c.time_s = i * o.frame_interval_s;
    c.exposure_s = o.exposure_s;
    c.f_number = o.f_number;
    c.focal_length_mm = o.focal_length_mm;
    c.focus_distance_m = o.focus_distance_m;
    validate_camera(c, "photo-scene view " + c.name);
    const std::string image_path = ds.path(ImageKind::kImages, c.name);
    if (!cv::imwrite(image_path, resized(cv::Rect(x, top, o.width, o.height))))
      throw InputError(image_path, "cannot write the view");
    write_depth(ds.path(ImageKind::kDepth, c.name), depth);
    ds.cameras.push_back(c);
    names.push_back(c.name);
  }
  summary.views = o.views;
  summary.resized_width = rw;
  summary.resized_height = rh;
  summary.pan_deg = (last_yaw - first_yaw) * 180 / kPi;

  ds.info.name = o.name.empty() ? fs::path(out.final_path()).filename().string() : o.name;
  ds.info.scene = ds.info.name;
  ds.info.weather = "clear";
  ds.info.splits = llff_splits(names);
  ds.info.splits_rule = std::string(kLlffSplitRule);
  ds.info.source = Json{{"photo", fs::absolute(o.photo).string()},
                        {"photo_sha256", sha256_file(o.photo)},
                        {"photo_size", {photo.cols, photo.rows}},
                        {"zoom", o.zoom},
                        {"pan_deg", summary.pan_deg},
                        {"depth", {{"model", "level camera over a ground plane, backdrop above the horizon"},
                                   {"camera_height_m", o.camera_height_m},
                                   {"backdrop_m", o.backdrop_m}}},
                        {"recipe", "weathergs photo-scene (docs/scenes.md)"}};
  write_dataset(ds);
  record_dataset_identity(out.path());
  out.commit();
  return summary;
}

}  // namespace weathergs::capture
