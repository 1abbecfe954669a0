// COLMAP 3.8 (CPU) as an external tool: triangulation with known poses (the sparse/0 export of a
// generated dataset), the mapper with unknown poses (imported footage), and model_analyzer.
#pragma once

#include <string>
#include <vector>

#include "core/camera.h"

namespace weathergs::capture {

struct ColmapOptions {
  std::string executable = "colmap";
  int num_threads = -1;  // COLMAP's -1 = all cores
  double timeout_s = 0;  // per COLMAP call; 0 = no limit

  void validate() const;  // InputError naming the field (executable set, num_threads -1 or >= 1, timeout >= 0)
};

struct ModelStats {
  int cameras = 0, images = 0, registered_images = 0, points = 0, observations = 0;
  double mean_track_length = 0;
  double mean_reprojection_error_px = 0;
};

// `colmap model_analyzer --path model_dir`, parsed. InputError if COLMAP cannot read the model.
ModelStats analyze_model(const std::string& model_dir, const ColmapOptions& options, const std::string& log_path);

struct TriangulationResult {
  ModelStats stats;
  double seconds = 0;
  // COLMAP triangulated nothing (it aborts then, see triangulate_known_poses): the model written has
  // the known poses and no points.
  bool no_points = false;
};

// Known poses: SIFT features of every view in image_dir (<name>.png), exhaustive matching, then
// `point_triangulator` with our cameras (intrinsics fixed; poses fixed), written as a text model to
// model_dir (created; must not exist). work_dir holds the database and logs. All views must share
// their intrinsics (one PINHOLE camera, like our scenes).
TriangulationResult triangulate_known_poses(const std::vector<Camera>& cameras, const std::string& image_dir,
                                            const std::string& work_dir, const std::string& model_dir,
                                            const ColmapOptions& options);

// `weathergs triangulate`: known-pose triangulation of an existing dataset (any dataset with a shared
// PINHOLE camera, e.g. one a user weathered with `weathergs weather`), as `generate` does it.
enum class TriangulateImages { kImages, kClean };  // images/ -> sparse/0, clean/ -> sparse_clean/0
enum class TriangulateViews { kAll, kTrain };      // all views (as generate) or the train split only
const char* to_string(TriangulateImages i);
const char* to_string(TriangulateViews v);

struct TriangulateOptions {
  TriangulateImages images = TriangulateImages::kImages;
  TriangulateViews views = TriangulateViews::kAll;
  bool force = false;  // replace an existing model
  ColmapOptions colmap;
  // Non-empty: write the model (and COLMAP's logs) here instead of into the dataset, which then stays
  // untouched (what `weathergs reconstruct` does for a dataset without points).
  std::string model_dir, logs_dir;
};

// Writes the model atomically (nothing on failure) and COLMAP's logs to logs/colmap[_clean]/.
// InputError: no dataset, no clean/ for kClean, an existing model without force, no matches.
// Whether the COLMAP text model in `model_dir` has at least one 3D point (points3D.txt).
bool has_sfm_points(const std::string& model_dir);

TriangulationResult triangulate_dataset(const std::string& dataset_dir, const TriangulateOptions& options,
                                        std::string* model_dir = nullptr);

struct MapperResult {
  ModelStats stats;
  std::vector<Camera> cameras;     // registered views, named by file stem, in name order
  std::vector<std::string> unregistered;
  double seconds = 0;
};

// Unknown poses: features, sequential or exhaustive matching, the mapper with the robust settings of
// ENVIRONMENT.md (PINHOLE, one camera), keeping the largest model, written as text to model_dir.
MapperResult map_unknown_poses(const std::string& image_dir, const std::string& work_dir, const std::string& model_dir,
                               const ColmapOptions& options);

}  // namespace weathergs::capture
