// The on-disk dataset of docs/formats.md: dataset.json + cameras.json + per-view image folders.
// Readers validate strictly: errors name the file, the JSON pointer and what was expected, and
// unknown keys are errors.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/dataset_layout.h"
#include "core/image.h"
#include "core/json_reader.h"

namespace weathergs {

struct DatasetInfo {
  std::string name;
  std::string scene;
  std::string weather = "clear";  // clear, rain, snow, or a documented combination ("rain+fog")
  std::map<std::string, std::vector<std::string>> splits;  // "train", "test", ...
  std::optional<std::string> splits_rule;                   // e.g. "llff_every_8"
  std::optional<Json> generator;  // owned by the generator: {version, seed, spec, stages, ...}
  std::optional<Json> source;     // imported footage: where the frames came from
  // The dataset's identity as written when it was made (core/dataset_identity.h: DatasetIdentity's
  // to_json with its files): a reader compares it with compute_dataset_identity of the files.
  std::optional<Json> identity;
};

struct Dataset {
  std::string root;
  DatasetInfo info;
  std::vector<Camera> cameras;  // in cameras.json order

  const Camera& camera(const std::string& view) const;  // InputError if unknown
  const std::vector<std::string>& split(const std::string& name) const;  // InputError if absent
  // "<root>/<folder of kind>/<view><ext of kind>", e.g. path(ImageKind::kImages, "007") -> ".../images/007.png".
  std::string path(ImageKind kind, const std::string& view) const;
  // "<root>/<folder of kind>".
  std::string dir(ImageKind kind) const;
  // "<root>/layers/<name>/<view><ext>": a float layer (or a per-view text manifest) of the generator.
  std::string layer_path(const std::string& name, const std::string& view, const std::string& ext = layout::kDepthExt) const;
  // "<root>/<relative>", e.g. file(layout::kSparseModelDir).
  std::string file(const std::string& relative) const;
  // Whether the folder of `kind` exists.
  bool has(ImageKind kind) const;
  // The clean image of a view: clean/<view>.png when the dataset has clean/, else images/<view>.png
  // (a clear dataset, or imported footage without ground truth).
  std::string clean_or_input_path(const std::string& view) const;
};

// The default split rule (LLFF / 3DGS): 0-based index % 8 == 0 is a test view.
constexpr const char* kLlffSplitRule = "llff_every_8";
std::map<std::string, std::vector<std::string>> llff_splits(const std::vector<std::string>& views,
                                                            int every = 8);

// View names must be file-system safe: [A-Za-z0-9._-]+, not starting with '.'.
bool is_safe_view_name(const std::string& name);
// The name of the index-th view of a numbered sequence, zero-padded: (7, 3) -> "007".
std::string numbered_view_name(int index, int digits = 3);

Dataset read_dataset(const std::string& root);
std::vector<Camera> read_cameras_json(const std::string& path);
DatasetInfo read_dataset_json(const std::string& path);

Json camera_to_json(const Camera& camera);
Camera camera_from_json(const JsonReader& reader);
Json dataset_info_to_json(const DatasetInfo& info);

// Atomic writers.
void write_cameras_json(const std::string& path, const std::vector<Camera>& cameras);
void write_dataset_json(const std::string& path, const DatasetInfo& info);
// Writes dataset.json and cameras.json into root (which must exist), after checking consistency.
void write_dataset(const Dataset& dataset);
// Consistency of info and cameras (split names refer to cameras; unique names): InputError otherwise.
void validate_dataset(const Dataset& dataset, const std::string& where);

}  // namespace weathergs
