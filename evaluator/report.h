// The results browser (`weathergs report SUITE_DIR -o REPORT_DIR`): a static site that opens from the
// file system, with no server and no network. From a suite folder (runs/<variant>/<method>/seed<S>/
// with results.json, renders/test/, curve.json and, for methods with the LED, detected/; data/<variant>/
// with the datasets) it writes:
//   REPORT_DIR/index.html, report.css, report.js   the page (evaluator/report_page/, embedded)
//   REPORT_DIR/data.js                             every number the page shows (window.WEATHERGS_REPORT)
//   REPORT_DIR/img/<variant>/<view>/               thumbnails (JPEG), full-size copies (PNG), absolute
//                                                  difference heat maps, mask overlays (RGBA PNG)
// Browsers refuse fetch() under file://, so the data is a script the page includes.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace weathergs::evaluator {

struct ReportOptions {
  std::string suite_dir;  // the workflow's output folder: runs/ and data/
  std::string out_dir;    // written atomically (replaced as a whole)
  int thumb_width = 200;  // thumbnails' width in pixels (the height keeps the aspect ratio)
  // Shown under provenance: the command that made the report, and weight files the runs do not
  // record themselves (the LPIPS model): name -> sha256.
  std::string command;
  std::vector<std::pair<std::string, std::string>> extra_weights;
  // Runs of one variant scored on datasets of different identities, or on another dataset than the
  // suite's data/<variant> that the page shows beside them: marked instead of refused
  // (evaluator/leaderboard.h).
  bool allow_mixed_data = false;
  // Runs whose recipes differ where they must agree (find_mixed_recipes): marked instead of refused.
  bool allow_mixed_recipes = false;
  // A results archive's suite folder (<root>/<suite>, e.g. benchmarks/results/quick; docs/archive.md),
  // empty for none: its runs of the suite's variants get a section of their own, "Converged (archive)",
  // with the same tables, how many cells of its matrix.json hold a run, and whether they were scored on
  // the suite's datasets; said plainly when it holds no run of them. Never mixed into the suite's rows:
  // a table holds one recipe, and a smoke run's is not the archive's.
  std::string converged_dir;
  // What the suite is, e.g. "A smoke run at 1000 iterations, not converged" (empty: none): shown at the
  // top of the page.
  std::string note;
  void validate() const;  // InputError naming the field
};

struct ReportSummary {
  int variants = 0, runs = 0, views = 0, images = 0;
  int converged_runs = 0;  // the archive's runs shown beside (ReportOptions::converged_dir)
  int64_t bytes = 0;  // the whole REPORT_DIR
  std::string index;  // REPORT_DIR/index.html
};

// InputError (naming the folder or file) when the suite has no runs, a run's results or renders are
// missing or unreadable, a variant's dataset is absent, or (unless allow_mixed_data) a run that
// records its dataset's identity was scored on other data than its variant's other runs or than
// data/<variant>, or (unless allow_mixed_recipes) runs of mixed recipes (leaderboard.h). Runs that
// record no identity are compared with each other only. A run without renders/test/ (restored from
// the results archive) is in the tables, curves and cost but has no column of images. suite_dir may
// also be a results archive's suite folder (<variant>/<method>/seed<S>/, no runs/ and no data/):
// then the report has the tables, curves, cost and provenance, and no variant pages. converged_dir:
// InputError when it is missing, is a suite folder (runs/, data/), or its runs of the suite's
// variants are unreadable or of mixed recipes (unless allow_mixed_recipes); its runs of other
// variants are not read.
ReportSummary write_report(const ReportOptions& options);

// The 95% confidence interval's half-width of a mean over n values with sample standard deviation
// s: t(0.975, n - 1) s / sqrt(n) (Student's t; 0 for n < 2).
double confidence_half_width_95(int n, double sample_std);

}  // namespace weathergs::evaluator
