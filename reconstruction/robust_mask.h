// RobustFilter: the distractor mask of the `robust-3dgs` baseline, without learned features. The rule
// is SpotLessSplats' robust baseline (Sabour et al. 2024, "RobustFilter" in its Fig. 8; gsplat
// examples/spotless_trainer.py run with --no-semantics --no-cluster), itself after RobustNeRF
// (Sabour et al. 2023):
//   1. per-pixel error e = mean over channels of |render - target|;
//   2. a pixel is an inlier when e < tau, tau the running 70th percentile of e: a histogram of e over
//      [0, 1] in 10000 bins, decayed by 0.95 and added to every iteration, tau = the lower edge of
//      the bin where its cumulative sum first reaches 70% (tau = 1 before the first update: all
//      pixels inliers); it is updated only while the trainer densifies, then frozen;
//   3. a pixel is kept when it is an inlier or more than half of its 3x3 neighbourhood (zero
//      padded, itself included) is;
//   4. annealed warm-up: a pixel the rule excludes is still kept with probability
//      alpha = exp(beta * floor((1 + step) / 1.5)), beta = -3e-3 (step = iteration - 1), drawn per
//      pixel (Bernoulli), so early iterations see nearly every pixel.
// Deviation, documented in docs/reconstruction.md: the mask enters our masked L1 + D-SSIM loss
// (valid-pixel normalisation, lambda 0.2); the reference weights an L1-only loss (ssim_lambda 0)
// and averages over all pixels. Like the reference, robust runs never reset opacity.
#pragma once

#include <cstdint>
#include <vector>

namespace weathergs::reconstruction {

struct RobustMaskOptions {
  double percentile = 0.7;        // robust_percentile
  double schedule_beta = -3e-3;   // schedule_beta (alpha annealing)
  int bins = 10000;               // bin_size of the error histogram over [0, 1]
  double histogram_decay = 0.95;  // the running histogram's decay per update
};

// Per-pixel error: mean over the three channels of |render - target| (H x W x 3 interleaved).
std::vector<float> robust_pixel_errors(const std::vector<float>& render, const std::vector<float>& target);

class RobustMask {
 public:
  explicit RobustMask(RobustMaskOptions options = {});

  // Appends to `invalid` (H x W, 1 = excluded from the loss; already sized, possibly holding the
  // view's own masks) the pixels the rule excludes at this (1-based) iteration, given this
  // iteration's robust_pixel_errors. The Bernoulli draws are keyed on (seed, iteration, row): the
  // same with any thread count.
  void exclude(const std::vector<float>& errors, int width, int height, int iteration, uint64_t seed,
               std::vector<uint8_t>* invalid) const;
  // Adds this iteration's errors to the running histogram and updates the threshold.
  void update(const std::vector<float>& errors);

  double threshold() const { return threshold_; }
  // Probability that an excluded pixel is still used at a (1-based) iteration.
  double keep_probability(int iteration) const;

  // Checkpoint state: the histogram and the threshold.
  const std::vector<double>& histogram() const { return histogram_; }
  void restore(std::vector<double> histogram, double threshold);
  const RobustMaskOptions& options() const { return options_; }

 private:
  RobustMaskOptions options_;
  std::vector<double> histogram_;
  double threshold_ = 1.0;
};

}  // namespace weathergs::reconstruction
