// Our paper-protocol tables set beside the WeatherGS paper's own (`weathergs leaderboard --paper
// --against-paper benchmarks/paper_tables.json`): the ranking of the five methods both share, with
// Kendall's tau, and each reading the paper's tables support, marked reproduced or not.
//
// What "reproduced" means, per kind of reading:
//   - a winner (best average PSNR / LPIPS): our best competitor is the same method;
//   - a difference (WeatherGS - 3DGS, ...): ours has the paper's sign; when ours rests on two or more
//     paired runs and its 95% interval contains 0, it is "unresolved" instead;
//   - an order (both ablations below the full method, ...): ours has the same order;
//   - a cost ratio (the NeRF backend against 3DGS): ours lies on the same side of 1.
// A reading whose methods did not run is "not run".
#pragma once

#include <map>
#include <string>
#include <vector>

#include "evaluator/paper_tables.h"

namespace weathergs::evaluator {

struct PublishedMetrics {
  double psnr = 0, ssim = 0, lpips = 0;
};

// The paper's tables as transcribed (benchmarks/paper_tables.json, its format in docs/evaluator.md).
struct PublishedTables {
  std::string source;
  // weather ("snow", "rain") -> our method name -> the paper's average over its three scenes.
  std::map<std::string, std::map<std::string, PublishedMetrics>> averages;
  std::vector<std::string> shared_methods;     // our names of Table I's rows, in the paper's order
  std::map<std::string, PublishedMetrics> ablation;  // our method name -> Table III
  // Table IV's backends: training minutes, render seconds per view, GPU memory (GB).
  double nerf_train_min = 0, gs_train_min = 0, nerf_render_s = 0, gs_render_s = 0, nerf_memory_gb = 0,
         gs_memory_gb = 0;
};

PublishedTables read_published_tables(const std::string& path);  // InputError naming file and key

// The agreement section, in Markdown.
std::string render_agreement(const PaperTables& ours, const PublishedTables& paper);

}  // namespace weathergs::evaluator
