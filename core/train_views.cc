#include "core/train_views.h"

#include <algorithm>
#include <filesystem>

#include "core/dataset_layout.h"
#include "core/error.h"
#include "core/image.h"

namespace weathergs {

namespace fs = std::filesystem;

const char* to_string(TrainImages images) { return images == TrainImages::kClean ? "clean" : "images"; }

const char* to_string(TrainMasks masks) {
  switch (masks) {
    case TrainMasks::kNone: return "none";
    case TrainMasks::kLens: return "lens";
    case TrainMasks::kParticles: return "particles";
    case TrainMasks::kAll: return "all";
  }
  WGS_CHECK(false);
}

TrainImages parse_train_images(const std::string& text, const std::string& where) {
  for (TrainImages v : {TrainImages::kImages, TrainImages::kClean})
    if (text == to_string(v)) return v;
  throw InputError(where, "expected \"images\" or \"clean\", got \"" + text + "\"");
}

TrainMasks parse_train_masks(const std::string& text, const std::string& where) {
  for (TrainMasks v : {TrainMasks::kNone, TrainMasks::kLens, TrainMasks::kParticles, TrainMasks::kAll})
    if (text == to_string(v)) return v;
  throw InputError(where, "expected one of none, lens, particles, all; got \"" + text + "\"");
}

void TrainInputs::validate(const std::string& where) const {
  if (!masks_dir.empty() && masks != TrainMasks::kNone)
    throw InputError(where, std::string("masks is \"") + weathergs::to_string(masks) + "\" and masks_dir is \"" + masks_dir +
                                "\": give one source of masks");
}

std::string TrainInputs::to_string() const {
  std::string s = images_dir.empty() ? std::string("images ") + weathergs::to_string(images) : "images_dir " + images_dir;
  s += masks_dir.empty() ? std::string(", masks ") + weathergs::to_string(masks) : ", masks_dir " + masks_dir;
  if (!points_dir.empty()) s += ", points_dir " + points_dir;
  return s;
}

std::vector<TrainView> load_train_views(const Dataset& dataset, const TrainInputs& inputs) {
  inputs.validate("train inputs");
  std::vector<TrainView> views;
  const auto& names = dataset.split("train");
  if (names.empty()) throw InputError(dataset.file(layout::kDatasetJson) + ":/splits/train", "the train split is empty");
  auto folder_file = [](const std::string& dir, const std::string& view) {
    return (fs::path(dir) / (view + layout::kImageExt)).string();
  };
  std::vector<ImageKind> mask_kinds;
  if (inputs.masks == TrainMasks::kLens || inputs.masks == TrainMasks::kAll) mask_kinds.push_back(ImageKind::kLensMask);
  if (inputs.masks == TrainMasks::kParticles || inputs.masks == TrainMasks::kAll)
    mask_kinds.push_back(ImageKind::kParticleMask);
  for (const std::string& name : names) {
    TrainView v;
    v.camera = dataset.camera(name);
    const std::string ipath =
        inputs.images_dir.empty()
            ? dataset.path(inputs.images == TrainImages::kClean ? ImageKind::kClean : ImageKind::kImages, name)
            : folder_file(inputs.images_dir, name);
    const Image img = to_rgb(read_image(ipath));
    if (img.width != v.camera.width || img.height != v.camera.height)
      throw InputError(ipath, "image is " + img.to_string() + ", camera '" + name + "' expects " +
                                  std::to_string(v.camera.width) + "x" + std::to_string(v.camera.height));
    require_finite(img, ipath);
    v.rgb.assign(img.data.begin(), img.data.end());
    for (float& x : v.rgb) x = std::clamp(x, 0.f, 1.f);
    std::vector<std::string> mask_paths;
    if (!inputs.masks_dir.empty()) mask_paths.push_back(folder_file(inputs.masks_dir, name));
    for (ImageKind k : mask_kinds) {
      const std::string mpath = dataset.path(k, name);
      // A dataset has masks/particles only where a particle effect ran, masks/lens only with drops.
      if (!dataset.has(k) && inputs.masks == TrainMasks::kAll) continue;
      mask_paths.push_back(mpath);
    }
    for (const std::string& mpath : mask_paths) {
      const Image m = read_mask(mpath);
      if (m.width != v.camera.width || m.height != v.camera.height)
        throw InputError(mpath, "mask is " + m.to_string() + ", expected the camera's size");
      v.invalid.resize(m.num_pixels(), 0);
      for (size_t p = 0; p < m.num_pixels(); ++p) v.invalid[p] |= m.data[p] > 0.5f ? 1 : 0;
    }
    views.push_back(std::move(v));
  }
  return views;
}

}  // namespace weathergs
