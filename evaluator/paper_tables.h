// The WeatherGS paper's four tables from a suite's results (`weathergs leaderboard --paper`):
//   Table I   snow: one column group per scene + Average (PSNR up, SSIM up, LPIPS down);
//   Table II  rain: the same; other weathers follow as further tables;
//   Table III ablation (weathergs-no-aef, weathergs-no-led, weathergs) averaged over every variant;
//   Table IV  computational cost per method: training time, restoration (AEF + LED) time, render
//             time per view, peak memory, Gaussians.
// The oracle and gt-masks are reference lines: listed last, marked, never in bold. Repeated runs of
// one cell (seeds) show mean ± the half-width of the 95% Student-t interval, and so do averages over
// scenes when several seeds ran on every scene. A last table gives paired differences (same variant,
// same seed) with their intervals: WeatherGS - 3DGS, each ablation - the full method, GS-W - 3DGS and
// DerainNeRF - NeRF. Results on other data than their variant's, and results of mixed recipes, are
// refused or, when allowed, marked (leaderboard.h): in the quality tables' cells, the ablation's
// averages and the differences' rows.
#pragma once

#include <string>
#include <vector>

#include "evaluator/leaderboard.h"
#include "evaluator/statistics.h"

namespace weathergs::evaluator {

// One method's cost, the mean over its runs (all variants and seeds) of the numbers its results
// files record in method_info (methods/reconstruct.cc); a number no run records is NaN (printed "–").
struct CostRow {
  std::string method;
  int runs = 0;
  double train_seconds = 0, train_seconds_std = 0;
  // Mean CPU seconds of the training (method_info.train_cpu_seconds, every thread's): NaN unless
  // every run of the method records them. Wall seconds grow when jobs share cores; these do not.
  double train_cpu_seconds = 0;
  double restoration_seconds = 0;  // filter_seconds + detect_seconds; 0 for methods without either
  double render_ms_per_view = 0;
  double peak_rss_mb = 0;
  double gaussians = 0;
  bool reference = false;
};

// method - baseline over the (variant, seed) pairs both ran, per weather and over all ("all").
struct PairedDifference {
  std::string method, baseline, weather;
  MeanInterval psnr, ssim, lpips;  // lpips.n == 0 when a pair lacks LPIPS
  bool other_data = false;         // a pair holds a result on other data than its variant's
  bool other_recipe = false;       // a pair holds a result of another recipe than its method's
};

struct PaperTables {
  std::vector<LeaderboardTable> quality;  // Table I (snow), Table II (rain), then any other weather
  LeaderboardTable ablation;              // Table III; no methods when no ablation method ran
  std::vector<std::string> ablation_variants;  // the variants Table III averages over
  std::vector<CostRow> cost;              // Table IV, in the order of the quality tables' rows
  std::vector<PairedDifference> differences;  // for the comparisons that have pairs
  std::vector<std::string> data_notes;        // every mixed variant, for the tables that span weathers
  std::vector<std::string> recipe_notes;      // every group of mixed recipes, likewise
};

PaperTables build_paper_tables(const std::vector<LoadedResults>& results, const LeaderboardOptions& options = {});
// note: what the table set is (render_leaderboard's).
std::string render_paper_tables(const PaperTables& tables, TableFormat format, const std::string& note = "");

}  // namespace weathergs::evaluator
