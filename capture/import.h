// `weathergs import`: real footage (a video or a folder of images) -> a dataset without clean ground
// truth: keyframes, COLMAP's mapper (unknown poses), cameras.json, sparse/0, transforms.json.
#pragma once

#include <string>
#include <vector>

#include "capture/colmap.h"

namespace weathergs::capture {

struct ImportOptions {
  std::string video;       // a video file OpenCV can decode (mp4, avi, ...), or
  std::string images_dir;  // a folder of images (png, jpg, jpeg, tif), taken in name order
  int every = 10;          // keep every N-th video frame (>= 1)
  int max_frames = 400;    // stop after this many keyframes (>= 3)
  int max_size_px = 1600;  // downscale so the long side is at most this (0 = keep)
  std::string name;        // dataset name; empty: the output folder's name
  std::string weather = "unknown";  // what the footage shows: clear, rain, snow, ... or unknown
  ColmapOptions colmap;

  void validate() const;  // InputError naming the option
};

struct ImportSummary {
  int frames = 0, registered = 0;
  ModelStats stats;
  double extract_s = 0, colmap_s = 0;
};

// Writes out_dir atomically: images/<view>.png (registered keyframes only, views "00000", ... by
// keyframe index), cameras.json (PINHOLE from COLMAP; time_s = frame index / fps for video, 0 for
// images; exposure_s 0 = unknown), dataset.json (LLFF split, `source` with the footage and the
// unregistered frames, no `generator`), sparse/0 and transforms.json. No clean/ or depth/.
ImportSummary import_footage(const ImportOptions& options, const std::string& out_dir);

}  // namespace weathergs::capture
