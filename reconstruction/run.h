// Whole training and rendering runs on a dataset (what `weathergs train` and `weathergs render` do).
//
// A run folder holds:
//   run.json          {"format": "weathergs-3dgs-run", "version": 1, "complete": bool, "dataset": ...,
//                      "images": ..., "masks": ..., "iterations": done, "sh_degree": ...,
//                      "num_gaussians": ..., "train_seconds": ..., "peak_rss_mb": ..., "options": {...}}
//   point_cloud.ply   the standard 3DGS PLY (written at every checkpoint and at the end)
//   checkpoint.bin    parameters + Adam state for --resume
// Every file is written atomically; run.json is rewritten at each checkpoint with "complete": false
// and at the end with "complete": true.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "core/dataset.h"
#include "reconstruction/trainer.h"

namespace weathergs::recon {

struct TrainRunOptions {
  std::string dataset;          // dataset root
  std::string images = "images";  // "images", "clean", or a folder with <view>.png
  std::string masks = "none";     // "none", "lens", or a folder with <view>.png (255 = masked out)
  std::string out;              // run folder
  bool resume = false;          // continue from out/checkpoint.bin
  bool force = false;           // start over even if out holds a run
  int checkpoint_every = 1000;  // iterations between checkpoints (0 = only at the end)
  TrainOptions train;
};

// Loads the dataset's train-split views with the chosen images and masks. InputError names the file.
std::vector<TrainView> load_train_views(const Dataset& dataset, const std::string& images, const std::string& masks);

// Initial Gaussians: COLMAP points3D.txt of the dataset when present and non-empty, else random.
GaussianSet<float> initial_gaussians(const Dataset& dataset, const TrainOptions& options, std::string* source);

struct TrainRunResult {
  int iterations = 0;
  int64_t num_gaussians = 0;
  double train_seconds = 0, final_loss = 0, final_psnr = 0, peak_rss_mb = 0;
};

// The options a run folder was trained with (from its run.json), for --resume.
TrainRunOptions read_run_options(const std::string& run_dir);

// Per-iteration callback (progress reporting); may be empty.
using IterationCallback = std::function<void(const IterationStats&)>;
TrainRunResult train_run(const TrainRunOptions& options, const IterationCallback& on_iteration = {});

struct RenderRunOptions {
  std::string model;          // run folder
  std::string dataset;        // empty: the dataset recorded in run.json
  std::string split = "test";
  std::string out;            // renders folder (replaced atomically)
  std::string method = "3dgs";
};

struct RenderRunResult {
  int views = 0;
  double render_seconds = 0;
};
RenderRunResult render_run(const RenderRunOptions& options);

}  // namespace weathergs::recon
