// What a reconstruction trains on: which of a dataset's images and loss masks, or outside folders
// of <view>.png, and the loaded training views. Shared by the 3DGS trainer (reconstruction/) and the
// radiance-field backend (nerf/), so that every method reads its inputs the same way.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/dataset.h"
#include "core/json_fields.h"

namespace weathergs {

// Which of the dataset's image folders a run trains on.
enum class TrainImages { kImages, kClean };
// Which of the dataset's ground-truth masks are excluded from the loss (255 = masked out).
enum class TrainMasks { kNone, kLens, kParticles, kAll /* lens or particles */ };
const char* to_string(TrainImages images);
const char* to_string(TrainMasks masks);
TrainImages parse_train_images(const std::string& text, const std::string& where);  // InputError
TrainMasks parse_train_masks(const std::string& text, const std::string& where);

// The images and masks of a run: a dataset folder (by kind) or an outside folder of <view>.png.
struct TrainInputs {
  TrainImages images = TrainImages::kImages;
  std::string images_dir;               // non-empty: <images_dir>/<view>.png instead of `images`
  TrainMasks masks = TrainMasks::kNone;
  std::string masks_dir;                // non-empty: <masks_dir>/<view>.png (255 = masked out)
  // Non-empty: the COLMAP text model (points3D.txt) to initialize from instead of the dataset's
  // sparse/0, e.g. sparse_clean/0 for the oracle.
  std::string points_dir;

  void validate(const std::string& where) const;  // InputError naming the field and the rule
  bool operator==(const TrainInputs& o) const {
    return images == o.images && images_dir == o.images_dir && masks == o.masks && masks_dir == o.masks_dir &&
           points_dir == o.points_dir;
  }
  std::string to_string() const;
};

// TrainInputs' keys in a run record (run.json of both backends): an empty folder is written as null.
inline constexpr auto kTrainInputsFields = [](auto& s, auto& f) {
  f("images", s.images, json_fields::OneOf{TrainImages::kImages, TrainImages::kClean});
  f("images_dir", s.images_dir, json_fields::EmptyIsNull{});
  f("masks", s.masks, json_fields::OneOf{TrainMasks::kNone, TrainMasks::kLens, TrainMasks::kParticles, TrainMasks::kAll});
  f("masks_dir", s.masks_dir, json_fields::EmptyIsNull{});
  f("points_dir", s.points_dir, json_fields::EmptyIsNull{});
};

// One training image: camera, sRGB pixels in [0, 1] (H x W x 3) and an optional mask (H x W,
// nonzero = masked out; empty = all valid).
struct TrainView {
  Camera camera;
  std::vector<float> rgb;
  std::vector<uint8_t> invalid;
};

// Loads the dataset's train-split views with the chosen images and masks. InputError names the file.
std::vector<TrainView> load_train_views(const Dataset& dataset, const TrainInputs& inputs);

}  // namespace weathergs
