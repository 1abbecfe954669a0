// The WeatherGS paper's four tables from a suite's results (`weathergs leaderboard --paper`):
//   Table I   snow: one column group per scene + Average (PSNR up, SSIM up, LPIPS down);
//   Table II  rain: the same; other weathers follow as further tables;
//   Table III ablation (weathergs-no-aef, weathergs-no-led, weathergs) averaged over every variant;
//   Table IV  computational cost per method: training time, restoration (AEF + LED) time, render
//             time per view, peak memory, Gaussians.
// The oracle and gt-masks are reference lines: listed last, marked, never in bold. Repeated runs of
// one cell (seeds) show mean ± standard deviation.
#pragma once

#include <string>
#include <vector>

#include "evaluator/leaderboard.h"

namespace weathergs::evaluator {

// One method's cost, the mean over its runs (all variants and seeds) of the numbers its results
// files record in method_info (methods/reconstruct.cc); a number no run records is NaN (printed "–").
struct CostRow {
  std::string method;
  int runs = 0;
  double train_seconds = 0, train_seconds_std = 0;
  double restoration_seconds = 0;  // filter_seconds + detect_seconds; 0 for methods without either
  double render_ms_per_view = 0;
  double peak_rss_mb = 0;
  double gaussians = 0;
  bool reference = false;
};

struct PaperTables {
  std::vector<LeaderboardTable> quality;  // Table I (snow), Table II (rain), then any other weather
  LeaderboardTable ablation;              // Table III; no methods when no ablation method ran
  std::vector<std::string> ablation_variants;  // the variants Table III averages over
  std::vector<CostRow> cost;              // Table IV, in the order of the quality tables' rows
};

PaperTables build_paper_tables(const std::vector<LoadedResults>& results);
std::string render_paper_tables(const PaperTables& tables, TableFormat format);

}  // namespace weathergs::evaluator
