// Whole training and rendering runs on a dataset (what `weathergs train` and `weathergs render` do).
//
// A run folder holds:
//   run.json          {"format": "weathergs-3dgs-run", "version": 2, "complete": bool, "dataset": ...,
//                      "images": "images"|"clean", "images_dir": path|null, "masks": "none"|"lens"|
//                      "particles"|"all", "masks_dir": path|null, "points_dir": path|null (optional),
//                      "iterations": done, "sh_degree": ...,
//                      "num_gaussians": ..., "train_seconds": ..., "train_cpu_seconds": ... (every
//                      thread's; left out when resumed from a checkpoint that lacks them),
//                      "peak_rss_mb": ..., "options": {...}}
//   point_cloud.ply   the standard 3DGS PLY (written at every checkpoint and at the end)
//   checkpoint.bin    parameters + Adam state for --resume
//   snapshots/iter_NNNNNN.{ply,json}  the model at the iterations of `snapshot_at` (accuracy against
//                     time: json = {"iteration", "train_seconds", "num_gaussians"}); writing them is
//                     not counted in train_seconds
// Every file is written atomically; run.json is rewritten at each checkpoint with "complete": false
// and at the end with "complete": true.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/dataset.h"
#include "core/stage_output.h"
#include "core/train_views.h"
#include "reconstruction/trainer.h"

namespace weathergs::reconstruction {

// The training inputs (which images, masks and points) and the loaded views have their home in
// core/train_views.h: the NeRF backend (nerf/) reads the same ones.
using weathergs::load_train_views;
using weathergs::parse_train_images;
using weathergs::parse_train_masks;
using weathergs::to_string;
using weathergs::TrainImages;
using weathergs::TrainInputs;
using weathergs::TrainMasks;
using weathergs::TrainView;

struct TrainRunOptions {
  std::string dataset;          // dataset root
  TrainInputs inputs;
  std::string out;              // run folder
  bool resume = false;          // continue from out/checkpoint.bin
  bool force = false;           // start over even if out holds a run
  int checkpoint_every = 1000;  // iterations between checkpoints (0 = only at the end)
  // Iterations at which to keep a snapshot of the model (snapshots/); those >= the final iteration
  // are ignored (the final model is point_cloud.ply). Each must be >= 1.
  std::vector<int> snapshot_at;
  TrainOptions train;

  // InputError naming the field, its value and the rule (dataset and out required, ...).
  void validate() const;
};

// Initial Gaussians: COLMAP points3D.txt of inputs.points_dir (which must hold one) or else of the
// dataset's sparse/0 when present and non-empty, else random (init_random.h).
GaussianSet<float> initial_gaussians(const Dataset& dataset, const TrainInputs& inputs, const TrainOptions& options,
                                     const std::vector<TrainView>& train_views, std::string* source);
// Whether initial_gaussians starts from SfM points (so that the random initialization never runs).
bool starts_from_points(const Dataset& dataset, const TrainInputs& inputs);

struct TrainRunResult {
  int iterations = 0;
  int64_t num_gaussians = 0;
  double train_seconds = 0, final_loss = 0, final_psnr = 0, peak_rss_mb = 0;
  std::optional<double> train_cpu_seconds;  // unset when resumed from a checkpoint without them
};

// `train` with its length and budget resolved for the dataset's training views
// (TrainOptions::with_run_length): what a run of these options records and trains with.
TrainOptions run_length_for(const TrainOptions& train, const Dataset& dataset);

// The options a run folder was trained with (from its run.json), for --resume.
TrainRunOptions read_run_options(const std::string& run_dir);

// What the run folder `run_dir` holds against the trainer options `train`: stale when run.json's
// options record differs in any key (another length, seed or recipe is another model: the "why"
// reads "options.KEY: ..."), complete when it says so, partial when a checkpoint to resume from
// is there, absent otherwise. A run resumed from a partial one ends with the same model, bit for bit.
StageOutput run_output(const std::string& run_dir, const TrainOptions& train);

// Per-iteration callback (progress reporting); may be empty.
using IterationCallback = std::function<void(const IterationStats&)>;
TrainRunResult train_run(const TrainRunOptions& options, const IterationCallback& on_iteration = {});

// The snapshot files of a run folder at one iteration: ".ply" and ".json" appended by the caller.
std::string snapshot_stem(const std::string& run_dir, int iteration);

struct RenderRunOptions {
  std::string model;          // run folder
  int snapshot = 0;           // > 0: render the snapshot of that iteration instead of the final model
  std::string dataset;        // empty: the dataset recorded in run.json
  std::string split = "test";
  std::string out;            // renders folder (replaced atomically)
  std::string method = "3dgs";
  bool depth = false;         // also write <out>/depth/<view>.exr (planar depth, docs/formats.md)
  // Depth pixels whose accumulated opacity is below this are background (+inf): the model is too
  // transparent there to say where the surface is.
  double depth_min_opacity = 0.5;

  void validate() const;  // InputError naming the field and the rule
};

// Planar depth (camera z, m) of a trained model in one view: the opacity-weighted mean of the
// Gaussians' camera depths along each pixel, sum(w_i z_i) / sum(w_i) with the blending weights
// w_i = alpha_i T_i of the colour pass; +inf where sum(w_i) < min_opacity. Rendered with the colour
// rasterizer itself (colours replaced by depth, then by one), so it follows its sorting and cut-offs.
std::vector<float> render_depth(const GaussianSet<float>& g, const Camera& camera, double min_opacity);

struct RenderRunResult {
  int views = 0;
  double render_seconds = 0;
};
RenderRunResult render_run(const RenderRunOptions& options);

}  // namespace weathergs::reconstruction
