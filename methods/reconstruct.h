// One method on one dataset, end to end (`weathergs reconstruct`): SfM points when the dataset has
// none, training, test renders, evaluation against the clean ground truth.
//
// The run folder:
//   filtered/           the AEF's images of every view (+ masks/, filter.json: plugin chosen per view)
//   detected/           the LED's loss masks of every view (detect.json)
//   sparse/0/           COLMAP points triangulated here when the dataset has none (the dataset itself
//                       is never modified); logs/colmap/ its logs
//   model/              the training run (reconstruction/run.h: run.json, point_cloud.ply, checkpoint;
//                       radiance-field methods: nerf/run.h, run.json, field.bin, snapshots/ renders)
//   renders/test/       <view>.png and info.json (method, train/render seconds, peak memory, ...)
//   curve.json          accuracy against training time: the test metrics at the `eval_at` iterations
//                       (model/snapshots/) and at the end, with the training seconds to get there
//   results.json        evaluator/results.h, written last: its presence means the run is complete
// Resuming, one rule for every stage: each stage's output carries the settings record that made it
// (filtered/filter.json, detected/detect.json, model/run.json). Started again, a run reuses each
// output whose record matches what it asks for (training resumes from its checkpoint, to the same
// model byte for byte) and refuses (InputError) an output made with other settings, naming the
// stage, the setting and `force`. A complete run is refused unless `force`; `force` starts over.
// Every resource the run needs (weights, LPIPS, a writable --out) is checked before any stage.
#pragma once

#include <string>
#include <vector>

#include "capture/colmap.h"
#include "evaluator/evaluate.h"
#include "nerf/run.h"
#include "reconstruction/run.h"
#include "restoration/led/detect_dataset.h"
#include "restoration/aef/particle_filter.h"
#include "adaptation/led_adaptation.h"
#include "methods/method.h"

namespace weathergs::methods {

enum class PointsPolicy {
  kAuto,    // the dataset's points, else triangulate into the run folder, else (COLMAP finds nothing
            // or is missing) the trainer's photo-consistent random initialization, with a warning
  kDataset  // the dataset's points, else random initialization: never runs COLMAP
};

struct ReconstructOptions {
  std::string dataset;
  std::string out;
  Method method = Method::k3dgs;
  // The 3DGS trainer's options (3DGS methods; reconstruction/trainer.h); the method's recipe overlays
  // what sets it apart (robust mask, distractors, in the wild). train.seed is the run's seed, the
  // radiance field's too.
  reconstruction::TrainOptions train;
  int checkpoint_every = 1000;
  // Iterations at which the test views are also scored (curve.json), in 3DGS iterations: each is the
  // fraction it / train.iterations of a run, which every backend scores at the same point of its own
  // run (radiance field: it * nerf.iterations / train.iterations, rounded). Each must be >= 1 and at
  // most the resolved train.iterations (InputError before any stage): the end is the final model,
  // always a point of the curve.
  std::vector<int> eval_at;
  // The same as fractions of the run's resolved length (each in (0, 1]): max(1, floor(f x length)),
  // for a run whose length the schedule sets (the workflow's curve_fractions).
  std::vector<double> eval_fractions;
  bool force = false;  // remove what an earlier run left at `out` and start over
  PointsPolicy points = PointsPolicy::kAuto;
  capture::ColmapOptions colmap;
  evaluator::ScoringOptions scoring;
  restoration::aef::ParticleFilterOptions particle_filter;  // the top-hat's parameters (aef-tophat)
  // The learned AEF's weights folder (derain, desnow, selector; restoration/aef/filter_dataset.h): required
  // by weathergs, weathergs-no-led and weathergs-nerf.
  std::string aef_weights;
  std::string led_weights;  // weathergs, weathergs-no-aef: the LED weights stem (required for them)
  restoration::led::LedMaskOptions led_mask;
  // Adapt the LED to the dataset before it runs (`detect --adapt`; docs/restoration_led.md, "Adapted to
  // the scene"). Unset: the weights as they are. Ignored by weathergs-per-view (drops that move).
  std::optional<adaptation::LedAdaptOptions> led_adapt;
  // Radiance-field methods (nerf, derainnerf, weathergs-nerf, nerf-oracle); its seed is train.seed.
  nerf::NerfOptions nerf;

  void validate() const;  // InputError naming the field
};

struct ReconstructResult {
  evaluator::Results results;
  std::string initialization;  // "dataset sparse/0", "triangulated: N points", "random (...)"
  bool resumed = false;
  double train_seconds = 0, render_seconds_per_view = 0, peak_rss_mb = 0;
};

// The 3DGS trainer's options of a 3DGS method's run: options.train with what the method's recipe sets
// (the robust mask, distractor Gaussians, in the wild).
reconstruction::TrainOptions method_train_options(const ReconstructOptions& options);

// Whether the dataset holds the SfM points the method starts from (sparse/0; sparse_clean/0 for the
// oracles), so that the run neither triangulates nor initializes at random.
bool dataset_has_points(const Dataset& dataset, Method method);

// Progress: the trainer's per-iteration callback, and one line per stage (may be empty).
using StageCallback = std::function<void(const std::string& stage)>;
ReconstructResult reconstruct(const ReconstructOptions& options, const reconstruction::IterationCallback& on_iteration = {},
                              const StageCallback& on_stage = {});

}  // namespace weathergs::methods
