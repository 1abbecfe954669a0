// Regression checks (`weathergs check`): compare new results against a stored baseline with
// per-metric tolerances. A metric "got worse" when PSNR or SSIM dropped, or LPIPS rose, by more than
// its tolerance: the means with the mean tolerances, and every view with the per-view ones. Results
// are matched by dataset name; each side may hold one result per dataset.
//
// Only like is compared with like, else the check refuses (InputError, exit 2) before any verdict:
// the protocol and the ground truth's sha256 must be equal (a changed yardstick is an error, not a
// pass), and so must what the baseline records of how it was made, unless allowed explicitly: the
// dataset's identity (dataset_identity.sha256: the data the method read as well as the truth), the
// weights' sha256 (method_info.weights) and the recipe (method_info.method, method_description,
// iterations, schedule). A key the baseline does not record is not compared.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "evaluator/leaderboard.h"

namespace weathergs::evaluator {

struct CheckTolerances {
  double psnr = 0.2;    // dB
  double ssim = 0.005;
  double lpips = 0.005;
  // Per view: a view's metric moves more between runs than the mean over views does. Unset: this
  // factor times the mean tolerance (about sqrt(2) for the two test views of the quick profile,
  // rounded up).
  static constexpr double kPerViewFactor = 2.0;
  std::optional<double> view_psnr, view_ssim, view_lpips;
  double per_view(double mean_tol, const std::optional<double>& v) const { return v ? *v : kPerViewFactor * mean_tol; }
  void validate() const;  // InputError: tolerances must be finite and >= 0
  // A baseline's own tolerances: {"psnr": dB, "ssim": ..., "lpips": ..., "per_view": {"psnr", "ssim",
  // "lpips"}, "basis": "how they were set"} (all optional; unknown keys are errors). InputError names
  // the file and key.
  static CheckTolerances from_file(const std::string& path);
};

struct CheckOptions {
  CheckTolerances tolerances;
  bool allow_other_data = false;     // compare although the dataset identities differ
  bool allow_other_weights = false;  // compare although method_info.weights differ
  bool allow_other_recipe = false;   // compare although the recipe differs
};

struct CheckReport {
  bool passed = true;
  std::string text;  // readable per-scene report
  Json json;         // the same, machine-readable
};

CheckReport check_regression(const std::vector<LoadedResults>& baseline,
                             const std::vector<LoadedResults>& current, const CheckOptions& options);

}  // namespace weathergs::evaluator
