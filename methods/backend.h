// A reconstruction backend as a run sees it: a model folder that is trained (resumed when the
// backend keeps checkpoints), whose currency its own part judges, and that renders a split. 3DGS
// (reconstruction/, methods/backend_3dgs.cc) and the grid radiance field (nerf/, backend_nerf.cc)
// implement it; docs/extending.md says how to add one.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/stage_output.h"
#include "core/train_views.h"
#include "nerf/run.h"
#include "reconstruction/run.h"

namespace weathergs::methods {

// A point of a run given as a fraction of its length, so that backends whose iterations mean
// different things score at the same point of their runs: at(n) = max(1, round(num * n / den)).
struct RunFraction {
  int num = 0, den = 1;
  int at(int iterations) const;
};

struct TrainOutcome {
  bool resumed = false;
  double peak_rss_mb = 0;
};

struct RenderOutcome {
  int views = 0;
  double seconds = 0;
};

class Backend {
 public:
  virtual ~Backend() = default;
  // The run's length, in the backend's own iterations.
  virtual int iterations() const = 0;
  // The iterations of the snapshots the run keeps for the curve (sorted, unique, each < iterations()).
  virtual std::vector<int> snapshots() const = 0;
  // What the model folder holds against this run's settings, as the backend's part judges it.
  virtual StageOutput model_output() const = 0;
  // Trains, resuming a partial model; on_iteration sees every iteration (a nerf's stats as 3DGS's).
  virtual TrainOutcome train(const reconstruction::IterationCallback& on_iteration) = 0;
  // Renders the final model's `split` views into `out` (replaced).
  virtual RenderOutcome render(const std::string& split, const std::string& out) = 0;
  // The test renders of snapshot `iteration`: a folder to score. A backend that must render them
  // writes `scratch`, which the caller removes after scoring.
  virtual std::string snapshot_renders(int iteration, const std::string& scratch) = 0;
};

// What every backend is given: the dataset, the training inputs, the model folder, the method's
// name (written into the renders' info.json) and the snapshots as fractions of the run.
struct BackendRun {
  std::string dataset;
  TrainInputs inputs;
  std::string model_dir;
  std::string method;
  std::vector<RunFraction> snapshots;
};

// The snapshots' iterations in a run of `iterations`, in the order given (duplicates kept: a backend
// trainer accepts them) without those at or past the end.
std::vector<int> snapshot_iterations(const std::vector<RunFraction>& snapshots, int iterations);
// The same, sorted and unique: the iterations the curve scores.
std::vector<int> scored_snapshots(const std::vector<RunFraction>& snapshots, int iterations);

// 3DGS with the trainer's options as the method's recipe made them, checkpointing every
// `checkpoint_every` iterations (0: only at the end).
std::unique_ptr<Backend> make_3dgs_backend(BackendRun run, const reconstruction::TrainOptions& train, int checkpoint_every);
// The grid radiance field, checkpointing every `checkpoint_every` iterations (0: never).
std::unique_ptr<Backend> make_nerf_backend(BackendRun run, const nerf::NerfOptions& nerf, int checkpoint_every);

}  // namespace weathergs::methods
