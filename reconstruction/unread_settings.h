// Which options a user set that a 3DGS run would never read. `train` and `reconstruct` refuse such a
// value before any work (docs/reconstruction.md, "Options that cannot take effect") instead of
// recording it as though the run had used it: a run must be exactly what its record says.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include "reconstruction/trainer.h"

namespace weathergs::reconstruction {

// What the run's data decides, known once the dataset is read and before training.
struct RunContext {
  bool loss_mask = false;    // the loss excludes masked pixels (given masks, the LED's, robust-3dgs's)
  bool from_points = false;  // it starts from SfM points: the random initialization never runs
};

struct UnreadSetting {
  std::string key;  // TrainOptions' JSON key (run.json's "options")
  std::string why;  // why the run would never read it
};

// The first key of `options` (resolved: with_run_length) that `is_set` says the user set and that a
// run in `context` never reads: full_resolution_at without the resolution schedule, desplat's and
// gs-w-lite's settings on other runs, the random initialization's on a run from SfM points, the mask
// normalization without a mask, the large-Gaussian prune or densification settings where no
// densification step can use them, the blend-weight prune's past the run or without a step, a
// position-rate hold past the run, the inert max_screen_size_px. None when every set key is read.
std::optional<UnreadSetting> unread_setting(const TrainOptions& options, const RunContext& context,
                                            const std::function<bool(const std::string& key)>& is_set);

}  // namespace weathergs::reconstruction
