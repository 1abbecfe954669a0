// Exports of a dataset's cameras for other tools.
#pragma once

#include <string>
#include <vector>

#include "core/camera.h"
#include "core/json_reader.h"

namespace weathergs::capture {

// nerfstudio-style transforms.json: per-frame intrinsics (camera_model "OPENCV", zero distortion)
// and transform_matrix = world_from_camera in OpenGL axes (x right, y up, z backward), i.e. our
// world_from_camera with its y and z columns negated. file_path is "<image_folder>/<view>.png".
Json transforms_json(const std::vector<Camera>& cameras, const std::string& image_folder = "images");
void write_transforms_json(const std::string& path, const std::vector<Camera>& cameras,
                           const std::string& image_folder = "images");

}  // namespace weathergs::capture
