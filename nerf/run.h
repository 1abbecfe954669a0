// Whole radiance-field runs on a dataset, with the same contract as the 3DGS runs
// (reconstruction/run.h), so methods/ and the leaderboard treat every method alike.
//
// A run folder holds:
//   run.json     {"format": "weathergs-nerf-run", "version": 1, "complete": bool, "dataset", the
//                 inputs (images, images_dir, masks, masks_dir, points_dir), "iterations",
//                 "train_seconds", "train_cpu_seconds", "peak_rss_mb", "lattice": [nu, nv, nw], "occupied_cells",
//                 "near_m", "options": {...}}
//   field.bin    the trained field (field.h)
//   snapshots/iter_NNNNNN/  renders of `snapshot_split` at the `snapshot_at` iterations with their
//                info.json (a field is ~100 MB, so snapshots are kept as renders, not as models);
//                rendering them is not counted in train_seconds
//   checkpoint.bin  the trainer's state every `checkpoint_every` iterations (nerf/trainer.h), for
//                `resume`; about three fields' worth, so it is removed once the run is complete
// A run killed part way resumes from its last checkpoint and ends in the same field, byte for byte, as
// one that never stopped. Every file is atomic; writing checkpoints is not counted in train_seconds.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "core/stage_output.h"
#include "core/train_views.h"
#include "nerf/trainer.h"

namespace weathergs::nerf {

inline constexpr const char* kNerfRunFormat = "weathergs-nerf-run";

struct NerfRunOptions {
  std::string dataset;
  TrainInputs inputs;
  std::string out;
  bool force = false;   // replace a run the folder already holds
  bool resume = false;  // continue the incomplete run of these settings from out/checkpoint.bin
  int checkpoint_every = 1000;  // iterations between checkpoints (0: none)
  std::vector<int> snapshot_at;
  std::string snapshot_split = "test";
  std::string method = "nerf";  // written into the snapshots' info.json
  NerfOptions nerf;
  void validate() const;  // InputError naming the field
};

struct NerfRunResult {
  int iterations = 0;
  double train_seconds = 0, peak_rss_mb = 0, near_m = 0;
  std::optional<double> train_cpu_seconds;  // every thread's CPU seconds of the training
  int64_t lattice_points = 0, occupied_cells = 0;
  std::string near_source;  // "sfm points: N" or "default"
};

using NerfIterationCallback = std::function<void(const NerfIterationStats&)>;
NerfRunResult train_nerf_run(const NerfRunOptions& options, const NerfIterationCallback& on_iteration = {});

// What the run folder `run_dir` holds against a run of `options` on `dataset` with `inputs`, by the
// one resume rule of both backends (reconstruction/run.h run_output): stale when run.json is not a
// radiance field's, or records other data ("dataset", "images", "masks_dir", ...) or any other option
// ("options.KEY": the length, the seed, a TV weight, the lattice...), the "why" naming the first that
// differs; complete when it is a complete run of these settings; partial when it is an incomplete one
// with a checkpoint to resume from; absent otherwise.
StageOutput nerf_run_output(const std::string& run_dir, const std::string& dataset, const TrainInputs& inputs,
                            const NerfOptions& options);

// The folder of the renders kept at one snapshot iteration.
std::string nerf_snapshot_dir(const std::string& run_dir, int iteration);

struct NerfRenderOptions {
  std::string model;  // run folder (complete)
  std::string dataset;  // empty: the dataset recorded in run.json
  std::string split = "test";
  std::string out;  // renders folder (replaced atomically): <view>.png + info.json
  std::string method = "nerf";
  void validate() const;
};

struct NerfRenderResult {
  int views = 0;
  double render_seconds = 0;
};
NerfRenderResult render_nerf_run(const NerfRenderOptions& options);

}  // namespace weathergs::nerf
