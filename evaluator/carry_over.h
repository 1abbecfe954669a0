// Does a suite's verdict carry over to another? Two results archives (docs/archive.md) of the same
// variants at different profiles, e.g. the quick suite and the paper-profile check: per paired
// difference (method a minus method b) and metric, the per-variant differences in each suite, how
// many of the target's share the source's sign, a one-sided sign test over the variants, and the
// ratio of the mean differences (docs/results.md, the carry-over section).
#pragma once

#include <string>
#include <vector>

namespace weathergs::evaluator {

// The significance level of the sign test: with 5 variants all agreeing p = 1/32 passes; with 4 or
// fewer no outcome can, and the verdict says so rather than "does not hold".
inline constexpr double kCarryOverAlpha = 0.05;

struct CarryOverPair {
  std::string a, b;  // the difference a - b
};
// "a:b[,a:b...]" -> pairs; InputError naming the flag and the bad entry.
std::vector<CarryOverPair> parse_carry_over_pairs(const std::string& text, const std::string& flag);
// The paper matrix's paired differences: WeatherGS against 3DGS, the weather's whole cost (the oracle
// against 3DGS), what WeatherGS leaves of it (the oracle against WeatherGS), the AEF's part.
inline constexpr const char* kDefaultCarryOverPairs =
    "weathergs:3dgs,oracle:3dgs,oracle:weathergs,weathergs:weathergs-no-aef";

struct CarryOverRow {
  CarryOverPair pair;
  std::string metric;                // "psnr", "ssim", "lpips"
  std::vector<std::string> variants; // where both suites ran both methods at a common seed
  // Per variant: the mean over the suite's seeds where both methods ran of (a - b).
  std::vector<double> from, to;
  std::vector<int> from_seeds, to_seeds;  // how many seeds each variant's difference averages
  double from_mean = 0, to_mean = 0;
  int agree = 0;       // target variants whose difference has the sign of the source's mean
  double p = 1;        // P(X >= agree), X ~ Binomial(n, 1/2): the one-sided sign test
  std::string verdict; // "holds", "same sign on k of n, not significant", "too few variants", ...
};

struct CarryOver {
  std::string from_dir, to_dir;
  int from_runs = 0, to_runs = 0;
  std::vector<CarryOverRow> rows;  // per pair, per metric, in that order; pairs with no common variant left out
  std::vector<std::string> notes;  // the pairs left out and why
};

// Reads both archives; each suite's runs must agree on their recipes and datasets as one leaderboard's
// (find_mixed_recipes, find_mixed_data): InputError naming the files otherwise, and when a folder
// holds no archived run.
CarryOver carry_over(const std::string& from_dir, const std::string& to_dir, const std::vector<CarryOverPair>& pairs);
// Markdown: the summary table (one row per pair and metric), then per pair the per-variant PSNR
// differences of both suites.
std::string render_carry_over(const CarryOver& c);

}  // namespace weathergs::evaluator
