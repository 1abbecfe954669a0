// Regression checks (`weathergs check`): compare new results against a stored baseline with
// per-metric tolerances. A metric "got worse" when PSNR or SSIM dropped, or LPIPS rose, by more than
// its tolerance. Results are matched by dataset name; each side may hold one result per dataset.
#pragma once

#include <string>
#include <vector>

#include "evaluator/leaderboard.h"

namespace weathergs::evaluator {

struct CheckTolerances {
  double psnr = 0.2;    // dB
  double ssim = 0.005;
  double lpips = 0.005;
  void validate() const;  // InputError: tolerances must be finite and >= 0
  // A baseline's own tolerances: {"psnr": dB, "ssim": ..., "lpips": ..., "basis": "how they were set"}
  // (all optional; unknown keys are errors). InputError names the file and key.
  static CheckTolerances from_file(const std::string& path);
};

struct CheckReport {
  bool passed = true;
  std::string text;  // readable per-scene report
  Json json;         // the same, machine-readable
};

CheckReport check_regression(const std::vector<LoadedResults>& baseline,
                             const std::vector<LoadedResults>& current, const CheckTolerances& tolerances);

}  // namespace weathergs::evaluator
