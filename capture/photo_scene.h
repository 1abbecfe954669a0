// `weathergs photo-scene`: one photograph -> a clear dataset that the weather generator accepts
// (docs/scenes.md, "Photographs as clear scenes"). The views are crops of the photograph taken by a
// camera that pans about a fixed centre; the depth is synthetic (a ground plane below the horizon row,
// a backdrop above). It exists for the restoration training set, which needs crop variety from clean
// photographs: lens drops need only the image and the camera, airborne particles need some depth.
#pragma once

#include <string>

namespace weathergs::capture {

struct PhotoSceneOptions {
  std::string photo;             // png/jpg/tif as OpenCV decodes it
  int views = 16;                // >= 3; the LLFF split (every 8th a test view)
  int width = 300, height = 200; // view size in pixels (>= 16 each)
  // The photograph is resized (area) so its height is zoom * height; the views then pan across its
  // width (a photo narrower than one view at that size is an error).
  double zoom = 1.5;
  // The camera of the shipped scenes (docs/scenes.md): a 6.0 mm-wide sensor behind a 4.0 mm lens at
  // f/2.8 focused at 2 m, so lens drops defocus as on the benchmark.
  double sensor_width_mm = 6.0;
  double focal_length_mm = 4.0;
  double f_number = 2.8;
  double focus_distance_m = 2.0;
  double frame_interval_s = 0.5;  // time_s of view i = i * this (lens drops may slide)
  double exposure_s = 1.0 / 60;
  // Synthetic depth: the camera looks level from this height; a pixel below the horizon row (cy) sees
  // the ground at planar depth camera_height_m * fy / (v + 0.5 - cy), clamped to backdrop_m; the rest is
  // a backdrop at backdrop_m.
  double camera_height_m = 1.6;
  double backdrop_m = 30.0;
  std::string name;  // dataset and scene name; empty: the output folder's name

  void validate() const;  // InputError naming the option
};

struct PhotoSceneSummary {
  int views = 0;
  int resized_width = 0, resized_height = 0;  // the photograph after the zoom
  double pan_deg = 0;                         // yaw between the first and the last view
};

// Writes out_dir atomically: images/<view>.png ("000", "001", ...), depth/<view>.exr, cameras.json
// (thin-lens data included), dataset.json (weather "clear", LLFF split, `source` with the photograph and
// every parameter above). Deterministic: no randomness.
PhotoSceneSummary make_photo_scene(const PhotoSceneOptions& options, const std::string& out_dir);

}  // namespace weathergs::capture
