// The 3DGS optimization loop (graphdeco-inria gaussian-splatting train.py): Adam with the reference
// learning rates, SH degree schedule, adaptive density control, opacity reset, masked loss.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/error.h"
#include "core/json_reader.h"
#include "core/progress.h"
#include "core/train_views.h"
#include "reconstruction/gaussians.h"
#include "reconstruction/in_the_wild.h"
#include "reconstruction/loss.h"
#include "reconstruction/rasterizer.h"
#include "reconstruction/robust_mask.h"

namespace weathergs::reconstruction {

// Reference defaults (arguments/__init__.py OptimizationParams); iteration counts are 1-based as in
// train.py. validate() throws InputError naming the field, its value and the rule.
struct TrainOptions {
  // 0: the schedule's own length, resolved for the training data by with_run_length() (kFast: a
  // count from the number of training views; the others: the reference's 30000). > 0: that count.
  int iterations = 0;
  uint64_t seed = 0;
  double lambda_dssim = kLambdaDssim;
  double position_lr_init = 1.6e-4;   // times the scene extent; log-linear decay over `iterations`
  double position_lr_final = 1.6e-6;
  // The position learning rate stays at position_lr_init up to this iteration, then decays
  // log-linearly to position_lr_final at the end of the run, so that a short run's Gaussians still
  // move at the full rate while densification places them (Mini-Splatting2's compressed schedule).
  // 0 (default, the reference): the decay starts at iteration 0. Taken as given in every schedule.
  int position_lr_hold_until = 0;
  double feature_lr = 2.5e-3;         // SH DC; the higher SH coefficients use feature_lr / 20
  double opacity_lr = 0.025;
  double scaling_lr = 5e-3;
  double rotation_lr = 1e-3;
  double adam_beta1 = 0.9, adam_beta2 = 0.999, adam_eps = 1e-15;
  int max_sh_degree = 3;
  int sh_degree_interval = 1000;      // SH degree + 1 every this many iterations
  double percent_dense = 0.01;        // clone below / split above this fraction of the extent
  int densify_from = 500;             // densify when from < iteration < until, every interval
  int densify_until = 15000;
  int densification_interval = 100;
  double densify_grad_threshold = 2e-4;  // mean |dL/d mean2d| in NDC units
  int opacity_reset_interval = 3000;
  // The blend-weight prune (Mini-Splatting's simplification), for schedules without the opacity
  // reset: at each of these iterations, after its densification and Adam step, every training view
  // is rendered at full resolution and a Gaussian is removed when its largest blend weight
  // alpha * T over all their pixels (max_blend_weights, rasterizer.h) is below
  // blend_prune_threshold: it gives no pixel more than that share of its colour. Ascending, each
  // >= 1; taken as given in every schedule. Empty (default): never.
  std::vector<int> blend_prune_at;
  double blend_prune_threshold = 0.01;
  double min_opacity = 0.005;         // prune below
  int max_screen_size_px = 20;        // see docs/reconstruction.md: inert as in the reference
  double max_world_size = 0.1;        // prune scale > this fraction of the extent (after large_prune_from)
  // The length max_world_size is a fraction of. kCameraExtent: the cameras' extent (the reference's
  // getNerfppNorm radius) for every Gaussian. kDistance (default): per Gaussian, the larger of that
  // and its distance from the cameras' mean centre, so that the prune bounds a Gaussian's angular
  // size as seen from the rig. Inside the camera ring of a 360-degree capture both are the same; on
  // a forward-facing rig (extent ~1.5 m, scene 10-40 m deep) the reference's threshold removed the
  // sky and water after the first reset (docs/reconstruction.md, "Large-Gaussian prune").
  enum class LargePrune { kCameraExtent, kDistance };
  LargePrune large_prune = LargePrune::kDistance;
  // The large-Gaussian prune runs at densification steps after this iteration: the reference's first
  // opacity reset (graphdeco prunes large Gaussians from its first reset on, gsplat from step >
  // reset_every), scaled with the run like densify_from. It is its own field because short runs
  // never reset: tied to the reset, runs under ~6000 iterations never pruned, and one SfM outlier
  // near the rig grew into a veil in front of every view (docs/reconstruction.md).
  int large_prune_from = 3000;
  // Memory guard (docs/reliability.md, "Resources"): densification never grows the model beyond this
  // many Gaussians; when the candidates would, only those with the largest mean view-space gradient
  // (ties: lower index) are cloned or split. The trainer's peak memory is ~2.6 KiB per Gaussian at
  // 300x200 (measured), so 1.2M keeps a run under ~4 GB. The reference has no cap.
  int64_t max_gaussians = 1200000;
  std::array<double, 3> background = {0, 0, 0};  // sRGB in [0, 1]
  // The schedule (docs/schedules.md). The reference's counts (densify from 500 to
  // 15000 every 100, reset opacity every 3000, SH degree + 1 every 1000) are made for 30000
  // iterations; run as they are, `--iterations 3000` ends on a reset.
  // - kReference: those counts at 30000 iterations, the protocol's exact form; a shorter run scales
  //   densify_from, densify_until, large_prune_from and sh_degree_interval by s = iterations / 30000,
  //   so densification happens in the first half and the second half recovers.
  //   densification_interval keeps the reference's 100 (the time a new Gaussian gets to settle;
  //   scaled to 10 it ran away on heavy weather) unless that leaves fewer than 8 densification steps
  //   (runs under ~1600 iterations), and the reset interval keeps at least the reference's 30
  //   densification steps per reset, so runs up to 6000 iterations never reset. Only fields still
  //   at their reference value are changed; a value set by hand is kept.
  // - kFast (default): the same scaled form at a length from the data, kFastEpochs passes over the
  //   training views, with a Gaussian budget from the image size (kFastGaussiansPerPixel).
  // - kUnscaled: every count as given, at any length (for schedules set by hand).
  enum class Schedule { kFast, kReference, kUnscaled };
  Schedule schedule = Schedule::kFast;
  // kFast's length: passes over the training views, within [kFastMinIterations, 30000], and its
  // Gaussian budget per pixel of a training image. Chosen on a tuning scene, never a benchmark one:
  // on village_rain's oracle (quick profile, 14 views) the scaled form reached R - 0.3 dB at 7000
  // iterations, not at 5000, and the 30000-iteration model holds 1.2 Gaussians per pixel
  // (docs/record/convergence.md).
  static constexpr int kFastEpochs = 500;
  static constexpr int kFastMinIterations = 3000;
  static constexpr double kFastGaussiansPerPixel = 2.0;
  // Resolution schedule (reconstruction/resolution.h), in any schedule: the run starts on images
  // box-downsampled by downsample_start (1, 2, 4, 8 or 16), halving at equal steps to full resolution
  // at full_resolution_at of the run, with the Gaussian budget divided by the factor squared. 1 (the
  // default): full resolution throughout. Not the default: on the held-out village_rain oracle it
  // cost 0.8 dB against full resolution at 7000 iterations (docs/record/convergence.md). gs-w-lite
  // and robust-3dgs refuse it: their visibility maps and distractor masks (3x3 neighbourhoods, an
  // error percentile) are defined per full-resolution pixel.
  int downsample_start = 1;
  double full_resolution_at = 0.5;
  // kRobustFilter: the robust-3dgs baseline's per-pixel distractor mask (reconstruction/robust_mask.h)
  // is excluded from the loss on top of any given mask, and opacity is never reset (as in the
  // reference's robust runs; a reset interval set by hand is kept).
  enum class Robust { kNone, kRobustFilter };
  Robust robust = Robust::kNone;
  // How a masked loss is normalised (reconstruction/loss.h): kValid (ours: masked pixels count for
  // nothing, means over the valid pixels) or kReference (the WeatherGS release: the target's masked
  // pixels replaced by the render, means over all pixels).
  MaskNormalization mask_normalization = MaskNormalization::kValid;
  // Without COLMAP points (reconstruction/init_random.h): kPhotoConsistent places each random ray's
  // point where neighbouring train views agree in colour; kFrustum is the plain random cloud.
  enum class RandomInit { kFrustum, kPhotoConsistent };
  RandomInit random_init = RandomInit::kPhotoConsistent;
  // The desplat method (reconstruction/distractors.h): this many distractor Gaussians per training
  // view, rendered only for their own view, never exported. 0 = plain 3DGS.
  int distractors_per_view = 0;
  // Their opacity penalty: the loss gains weight x (image fraction the distractors' opacity covers),
  // so a distractor survives only where it explains more than the multi-view scene can. Ours, not
  // DeSplat's: without it the distractors took scene content (docs/reconstruction.md, "desplat").
  // 1.0 was the best of 0.01-1.0 on two weathered training scenes (not the benchmark's); a large
  // painted occluder wants ~0.01 (test reconstruction/trainer).
  double distractor_opacity_weight = 1.0;
  // The gs-w-lite method (reconstruction/in_the_wild.h): per-view affine appearance and a learned
  // per-view visibility map with GS-W's (1 - M)^2 regulariser, used after in_the_wild_from iterations.
  bool in_the_wild = false;
  int in_the_wild_from = 200;
  double visibility_weight = 0.2;
  int random_init_count = 50000;      // Gaussians when the dataset has no COLMAP points
  double random_init_near_m = 0.5;    // depth range (m) of the random initialization
  double random_init_far_m = 20.0;

  void validate(const std::string& where) const;
  Json to_json() const;
  static TrainOptions from_json(const JsonReader& r);  // a run record or checkpoint header
  // A file a user writes (--train-options): every key it leaves out keeps its default, also those
  // whose absence from a record means what older runs trained with (large_prune, large_prune_from).
  static TrainOptions from_user_json(const JsonReader& r);
  // The options the trainer runs with: the schedule scaled to `iterations` (kFast, kReference),
  // else *this. Needs a resolved length (with_run_length).
  TrainOptions effective() const;
  // The length and budget for training data of `views` views of at most `pixels` pixels each:
  // iterations 0 becomes the schedule's length, and kFast's budget caps max_gaussians when that is
  // still the default. Everything else is kept; a resolved set is returned as it is.
  TrainOptions with_run_length(int views, int64_t pixels) const;
  // The same for these training cameras: their count and the largest one's pixels.
  TrainOptions with_run_length(const std::vector<Camera>& train_cameras) const;
};
const char* to_string(TrainOptions::Schedule s);
// "fast" | "reference" | "unscaled" ("scaled", the name reference had before, is read as it);
// anything else throws InputError naming `where`.
TrainOptions::Schedule parse_schedule(const std::string& s, const std::string& where);
const char* to_string(TrainOptions::RandomInit r);
const char* to_string(TrainOptions::Robust r);
const char* to_string(TrainOptions::LargePrune p);
// "distance" | "camera_extent"; anything else throws InputError naming `where`.
TrainOptions::LargePrune parse_large_prune(const std::string& s, const std::string& where);

using weathergs::TrainView;  // core/train_views.h

// Mean of the camera centres, and their radius around it times 1.1 (getNerfppNorm): the "cameras
// extent".
Eigen::Vector3d rig_center(const std::vector<Camera>& cameras);
double scene_extent(const std::vector<Camera>& cameras);

// Thrown when a loss or gradient stops being finite; names the parameter, the Gaussian and the step.
class TrainingDiverged : public NumericalDivergence {
 public:
  using NumericalDivergence::NumericalDivergence;
};

struct IterationStats {
  int iteration = 0;
  double loss = 0, psnr = 0;
  int64_t num_gaussians = 0;
  bool densified = false;
  int downsample = 1;  // the factor the iteration's image was downsampled by (resolution schedule)
};

class Trainer {
 public:
  Trainer(std::vector<TrainView> views, GaussianSet<float> initial, const TrainOptions& options, double extent);

  // Runs iteration() + 1.
  IterationStats step();
  int iteration() const { return iteration_; }
  int sh_degree() const { return sh_degree_; }
  // Densification steps at which the max_gaussians guard held candidates back (0 = never).
  int densify_capped() const { return densify_capped_; }
  // Every Gaussian being optimised: the scene's and (desplat) the per-view distractors, see owners().
  const GaussianSet<float>& gaussians() const { return g_; }
  // The owner of each row of gaussians(): kSceneOwner or the training view's index.
  const std::vector<int32_t>& owners() const { return owner_; }
  // The scene alone: what is exported (point_cloud.ply) and rendered at test time.
  GaussianSet<float> scene_gaussians() const;
  int64_t num_distractors() const { return num_distractors_; }
  const InTheWild& in_the_wild() const { return wild_; }
  GaussianSet<float>& mutable_gaussians() {  // tests inject faults through this
    parameters_checked_ = false;
    return g_;
  }
  const TrainOptions& options() const { return requested_; }    // as given (run.json, resume)
  const TrainOptions& effective_options() const { return options_; }  // with the scaled schedule
  double extent() const { return extent_; }
  // Index into views of the image used at a (1-based) iteration: a fresh permutation every epoch.
  int view_for_iteration(int iteration) const;
  double position_lr(int iteration) const;
  // The blend-weight prune (TrainOptions::blend_prune_at): renders every training view (with
  // distractors, each with its own), removes each Gaussian whose largest blend weight over them is
  // below `threshold`, with its Adam moments and densification statistics; returns how many went.
  int64_t prune_by_blend_weight(double threshold);

  // Checkpoint: parameters, Adam state, densification statistics and the iteration (binary).
  // train_cpu_seconds: the CPU seconds of the training so far, unknown when a run resumed from a
  // checkpoint that did not record them.
  void save_checkpoint(const std::string& path, double train_seconds,
                       std::optional<double> train_cpu_seconds = std::nullopt) const;
  // Restores a checkpoint written with the same options; returns the train seconds stored in it
  // (and sets *train_cpu_seconds to its CPU seconds, unset when it records none).
  double load_checkpoint(const std::string& path, std::optional<double>* train_cpu_seconds = nullptr);

 private:
  // factor: this iteration's downsampling (resolution.h), which divides the budget by factor^2.
  void densify_and_prune(bool prune_large, int factor);
  void reset_opacity();
  // Returns false when a gradient or an updated parameter is not finite.
  bool adam_step();
  void check_finite_gradients() const;
  void check_finite_parameters() const;
  void check_finite_array(const std::vector<float>& a, ParamGroup group, int stride, const char* what) const;

  std::vector<TrainView> views_;
  // The resolution schedule's images: lowres_[k] holds every view downsampled by 2^(k+1).
  std::vector<std::vector<TrainView>> lowres_;
  TrainOptions requested_, options_;
  double extent_;
  Eigen::Vector3d rig_center_;  // mean of the training cameras' centres (the extent's centre)
  GaussianSet<float> g_, grad_, adam_m_, adam_v_;
  std::array<int64_t, 6> adam_steps_{};  // per ParamGroup
  std::vector<float> grad_accum_, max_radii_;
  std::vector<int32_t> grad_count_;
  RobustMask robust_mask_;
  std::vector<uint8_t> invalid_;  // this iteration's loss mask (view masks + robust exclusions)
  std::vector<float> robust_errors_;  // this iteration's per-pixel errors (exclude, then update)
  std::vector<float> v_ndc_, v_image_;
  RasterState<float> state_;
  std::vector<int32_t> owner_;  // per Gaussian: kSceneOwner or its training view (desplat)
  int64_t num_distractors_ = 0;
  std::vector<int64_t> rows_;  // this iteration's rendered rows when distractors exist
  GaussianSet<float> sub_, sub_grad_;
  InTheWild wild_;                              // gs-w-lite only
  std::vector<float> wild_render_, wild_target_;  // the images its loss compares
  int iteration_ = 0;
  int sh_degree_ = 0;
  int densify_capped_ = 0;
  bool parameters_checked_ = false;  // g_ is as the last Adam step (which checked it) left it
};

using weathergs::peak_rss_mb;  // core/progress.h

}  // namespace weathergs::reconstruction
