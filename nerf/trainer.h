// Training of the grid radiance field (docs/nerf.md): random rays from the training views' valid
// pixels, volume rendering, the masked photometric loss (MSE over the pixels that are not masked
// out, as NeRF and DerainNeRF), total variation on a random subset of lattice points, and Adam on
// the lattice points a batch touched (DVGO's learning rates). Coarse to fine: the lattice is
// resampled to finer levels at `upsample_at`.
//
// Deterministic: rays and jitter are keyed on (seed, iteration, ray); gradients are spread over the
// lattice in a fixed order (rays in fixed chunks, each lattice slab applying its chunks in order), so
// the same seed gives the same field with 1 or 2 threads.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/json_reader.h"
#include "core/train_views.h"
#include "nerf/field.h"

namespace weathergs::nerf {

struct NerfOptions {
  // 3000: on held-out clean scenes +0.66 dB and a third less LPIPS than 1500, which ends on the
  // second level of the coarse-to-fine schedule below, at 3.3x its time (docs/nerf.md, "Against
  // 3DGS on held-out scenes").
  int iterations = 3000;
  int batch_rays = 4096;
  uint64_t seed = 0;
  // The final lattice: one point per `pixels_per_cell` pixels of the mean focal length across the
  // image plane, `depth_cells` cells along disparity.
  double pixels_per_cell = 2.0;
  int depth_cells = 128;
  // Coarse to fine: the lattice starts at level_scales[0] x the final size (cells per axis) and is
  // resampled to level_scales[i] at upsample_at[i - 1]. The last scale must be 1.
  std::vector<double> level_scales = {0.5, 0.75, 1.0};
  std::vector<int> upsample_at = {1000, 2000};
  double alpha_init = 1e-2;  // opacity per grid cell of path at the start (DVGO's fine stage)
  // Adam (beta 0.9 / 0.99, DVGO), learning rates decayed exponentially to lr_final_factor x at the end.
  double lr_density = 0.1, lr_color = 0.1, lr_env = 0.05, lr_final_factor = 0.1;
  // Total variation (squared differences to the +u, +v, +w neighbours) on a random tv_fraction of
  // the lattice points per iteration, mean over them, times these weights. 1e-3: on held-out clean
  // scenes +0.9 to +1.3 dB over 1e-4 and above 3e-3; a larger fraction changes nothing (docs/nerf.md).
  double tv_density = 1e-3, tv_color = 1e-3, tv_fraction = 0.01;
  double near_m = 0;  // 0: from the SfM points (frustum.h near_from_points), else 1 m
  MarchSettings march;

  void validate(const std::string& where) const;  // InputError naming the field and the rule
  Json to_json() const;
  static NerfOptions from_json(const JsonReader& r);  // a run's record: every key required
  // A user's file (`reconstruct --nerf-options`): a key it leaves out keeps its default.
  static NerfOptions from_user_json(const JsonReader& r);
};

struct NerfIterationStats {
  int iteration = 0;  // 1-based, after the step
  double loss = 0, psnr = 0;
  int64_t lattice_points = 0, occupied_cells = 0, samples = 0;
};

class NerfTrainer {
 public:
  // `frame` covers every view to be rendered; views are the training views (masks: invalid pixels
  // are never sampled).
  NerfTrainer(std::vector<TrainView> views, const FrustumFrame& frame, const NerfOptions& options);
  NerfIterationStats step();
  int iteration() const { return iteration_; }
  const RadianceField& field() const { return field_; }
  const NerfOptions& options() const { return options_; }
  GridDims level_dims(int level) const;

  // Checkpoint (trainer_checkpoint.cc): the field, the optimizer state, the level and the iteration,
  // with the options that made them. A trainer built from the same views and options and restored
  // from it steps on to the same bits as one that never stopped. `run_state` belongs to the caller
  // (its clocks): stored as it is and returned by load_checkpoint. InputError naming the file and
  // what differs (an option, the frame, the size).
  void save_checkpoint(const std::string& path, const Json& run_state) const;
  Json load_checkpoint(const std::string& path);

 private:
  void start_level(int level);
  void prune_unseen();
  void add_tv();
  void adam_step();

  std::vector<TrainView> views_;
  NerfOptions options_;
  GridDims final_dims_;
  RadianceField field_;
  int iteration_ = 0, level_ = 0;
  std::vector<int64_t> valid_;  // view * pixels_per_view + pixel of every unmasked pixel
  int64_t pixels_per_view_ = 0;
  std::vector<float> grad_, m_, v_;  // kStride per lattice point
  std::vector<uint8_t> touched_;
  std::vector<float> env_grad_, env_m_, env_v_;
  int adam_steps_ = 0;
};

}  // namespace weathergs::nerf
