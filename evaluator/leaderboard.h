// Leaderboards in the layout of the WeatherGS paper's tables: one table per weather, rows = methods,
// column groups = scenes (PSNR up, SSIM up, LPIPS down) plus an Average group, best value per column
// in bold. Repeated results of one (method, scene, weather), e.g. several seeds, are averaged and
// shown with their standard deviation and count.
//
// One column holds results of one dataset: results of one variant (scene and weather) whose dataset
// identities differ (results.json's dataset_identity; one that records none differs from one that
// does) are refused, naming both files and both hashes, unless allowed; then the cells holding them
// are marked with a dagger and a note names the identities.
#pragma once

#include <limits>
#include <set>
#include <string>
#include <vector>

#include "evaluator/results.h"

namespace weathergs::evaluator {

enum class TableFormat { kMarkdown, kCsv, kLatex, kHtml };
TableFormat parse_table_format(const std::string& name);  // md|csv|latex|html, else InputError

struct LoadedResults {
  std::string path;
  Results results;
};

// One cell: the mean over repeated results and, when there are several, their spread.
struct CellStats {
  int n = 0;
  double psnr = 0, ssim = 0, lpips = 0;
  double psnr_std = 0, ssim_std = 0, lpips_std = 0;
  // Half-widths of the 95% Student-t intervals of the means (evaluator/statistics.h); NaN when n < 2.
  double psnr_ci = kNoInterval, ssim_ci = kNoInterval, lpips_ci = kNoInterval;
  bool has_lpips = false;
  // Holds a result scored on other data than its column's (LeaderboardOptions::allow_mixed_data):
  // marked, never in bold.
  bool other_data = false;
  // Holds a result made with another recipe than the rest of its method's, or with none recorded
  // (LeaderboardOptions::allow_mixed_recipes): marked, never in bold.
  bool other_recipe = false;
  static constexpr double kNoInterval = std::numeric_limits<double>::quiet_NaN();
};

struct LeaderboardTable {
  std::string weather;
  std::string title;                 // heading; empty: "Weather: <Weather>"
  std::vector<std::string> scenes;   // order of first appearance
  std::vector<std::string> methods;  // order of first appearance
  // cells[method][scene]; n == 0 when the method has no result for that scene.
  std::vector<std::vector<CellStats>> cells;
  std::vector<CellStats> average;    // per method: mean over scenes; n == 0 unless all scenes present
  // Per method (empty = none): a reference line such as the oracle, shown but never in bold.
  std::vector<bool> reference;
  std::string average_label = "Average";
  std::string average_note = "Average: mean over scenes, only for methods with every scene.";
  // Cells with repeated runs show ± the 95% t-interval's half-width (the paper tables) instead of ± the
  // standard deviation.
  bool ci95 = false;
  Protocol protocol;
  // One line per column whose results were scored on more than one dataset (allow_mixed_data).
  std::vector<std::string> data_notes;
  // One line per group of runs made with more than one recipe (allow_mixed_recipes).
  std::vector<std::string> recipe_notes;
};

struct LeaderboardOptions {
  // Results of one variant on datasets of different identities: marked instead of refused.
  bool allow_mixed_data = false;
  // Results whose recipes differ where they must agree (find_mixed_recipes): marked instead of refused.
  bool allow_mixed_recipes = false;
};

// Which results were scored on other data than their variant's (scene and weather): per variant, the
// identity most of its results record (the first such on a tie) is the variant's; every result with
// another identity or none is odd, unless no result of the variant records one. Without
// allow_mixed_data the first odd result is an InputError naming it and a result of the variant's
// identity, with both hashes.
struct MixedData {
  struct Variant {
    std::string weather, scene;
    std::string identities;  // "2 on 1a2b3c4d5e6f (the column's); 1 on 9f8e7d6c5b4a (noise)"
  };
  std::set<const LoadedResults*> odd;
  std::vector<Variant> mixed;  // the variants with odd results, in order of first appearance
  bool is_odd(const LoadedResults& r) const { return odd.count(&r) > 0; }
};
MixedData find_mixed_data(const std::vector<LoadedResults>& results, const LeaderboardOptions& options);
// The marker of a cell holding odd results, and the note that explains it under a table.
inline constexpr const char* kOtherDataMarker = "†";
std::string other_data_note(const std::vector<std::string>& lines);  // "" for none

// Which results were made with another recipe than the rest of their group (evaluator/recipe.h;
// docs/evaluator.md, "One recipe"). The results given to one leaderboard must agree, where a recipe
// is recorded, on:
//   - the scoring (the protocol and the LPIPS weights), over all results;
//   - the trainer-numerics version, over all results of one backend (3DGS, the radiance field);
//   - everything but what the dataset makes of the recipe (recipe_across_datasets: the options,
//     restoration settings, weights, numerics, scoring, points policy), over all results of one
//     method, across variants and seeds;
//   - everything but the dataset's identity (which find_mixed_data judges), over the results of one
//     method on one variant: the run length and budget the schedule gave, the points.
// Different methods differ by design and are not compared otherwise; a result that records no recipe
// (made before recipes were, or a method of one's own scored by `evaluate`) takes part in its
// method's groups only. Per group, the recipe most of its results record (the first on a tie) is the
// group's; a result with another, or with none recorded, is odd, unless no result of the group
// records one. Without
// allow_mixed_recipes the first odd result is an InputError naming it, a result of the group's
// recipe and the first key where they differ.
struct MixedRecipes {
  std::set<const LoadedResults*> odd;
  // Per group with odd results: "weathergs: 2 on recipe 1a2b3c4d5e6f (the group's); 1 on recipe
  // 9f8e7d6c5b4a (options/densify_until)", with the weathers of its odd results.
  struct Group {
    std::set<std::string> weathers;
    std::string note;
  };
  std::vector<Group> groups;
  bool is_odd(const LoadedResults& r) const { return odd.count(&r) > 0; }
  std::vector<std::string> notes(const std::string& weather) const;  // "" = every weather
};
MixedRecipes find_mixed_recipes(const std::vector<LoadedResults>& results, const LeaderboardOptions& options);
inline constexpr const char* kOtherRecipeMarker = "‡";
std::string other_recipe_note(const std::vector<std::string>& lines);  // "" for none
// A cell's markers: kOtherDataMarker and/or kOtherRecipeMarker ("" for none).
std::string cell_marks(const CellStats& c);

// oracle (3DGS on the clean images), nerf-oracle and gt-masks (ground-truth masks): bounds, not
// competitors. Every table marks them as reference lines: shown, never in bold.
bool is_reference_method(const std::string& method);

// Groups results into tables. Results in one table must share a protocol, and results in one column
// a dataset unless options allow mixing (InputError naming files).
std::vector<LeaderboardTable> build_leaderboard(const std::vector<LoadedResults>& results,
                                                const LeaderboardOptions& options = {});
// note: what the table set is, e.g. "a smoke run at 1000 iterations, not converged" (empty: none): the
// first paragraph under the title in Markdown and HTML, comment lines in LaTeX. CSV holds data only:
// a note there is an InputError.
std::string render_leaderboard(const std::vector<LeaderboardTable>& tables, TableFormat format,
                               const std::string& note = "");

// Mean and population standard deviation of x (NaN for none); an infinite value (PSNR of identical
// images) makes the mean +inf and the spread 0.
void mean_std(const std::vector<double>& x, double& mean, double& sd);

// Pieces of render_leaderboard for documents that add their own tables (evaluator/paper_tables.h).
std::string render_table(const LeaderboardTable& table, TableFormat format, bool csv_header);
std::string document_begin(TableFormat format, const std::string& title, const std::string& note = "");
// InputError when `note` cannot go into a table of `format` (CSV holds data only).
void check_note(TableFormat format, const std::string& note);
std::string document_end(TableFormat format);
std::string csv_escape(const std::string& s);
std::string latex_escape(const std::string& s);
std::string html_escape(const std::string& s);

}  // namespace weathergs::evaluator
