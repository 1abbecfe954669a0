#include "capture/exports.h"

#include "core/atomic_file.h"

namespace weathergs::capture {

Json transforms_json(const std::vector<Camera>& cameras, const std::string& image_folder) {
  Json frames = Json::array();
  for (const Camera& c : cameras) {
    Eigen::Matrix4d m = c.world_from_camera();
    m.col(1) *= -1.0;  // OpenCV -> OpenGL camera axes
    m.col(2) *= -1.0;
    Json rows = Json::array();
    for (int i = 0; i < 4; ++i) rows.push_back({m(i, 0), m(i, 1), m(i, 2), m(i, 3)});
    frames.push_back({{"file_path", image_folder + "/" + c.name + ".png"},
                      {"transform_matrix", rows},
                      {"fl_x", c.fx}, {"fl_y", c.fy}, {"cx", c.cx}, {"cy", c.cy}, {"w", c.width}, {"h", c.height}});
  }
  Json j = {{"camera_model", "OPENCV"}, {"k1", 0.0}, {"k2", 0.0}, {"p1", 0.0}, {"p2", 0.0}, {"frames", frames}};
  if (!cameras.empty()) {
    // Shared intrinsics at the top level too (most readers look there first).
    const Camera& c = cameras.front();
    j["fl_x"] = c.fx, j["fl_y"] = c.fy, j["cx"] = c.cx, j["cy"] = c.cy, j["w"] = c.width, j["h"] = c.height;
  }
  return j;
}

void write_transforms_json(const std::string& path, const std::vector<Camera>& cameras, const std::string& image_folder) {
  write_file_atomic(path, transforms_json(cameras, image_folder).dump(1));
}

}  // namespace weathergs::capture
