// The results archive (docs/archive.md): finished runs kept in git as small records, so that a
// suite longer than any machine lives resumes where the last one stopped.
//
//   <suite_dir>/<variant>/<method>/seed<N>/   (suite_dir = <root>/<suite>, e.g. benchmarks/results/quick)
//     results.json     the run's results (evaluator/results.h), with its recipe and fingerprint
//     curve.json       accuracy against training time
//     run.json         the training's settings record (the run's model/run.json)
//     provenance.json  {"format": "weathergs-archive-run", "version": 1, "added", "threads",
//                       "cpu_seconds", "source"}; the dataset's sha256, the commit that trained the run
//                       and the recipe's fingerprint are results.json's
// Renders and models stay out: a record file over kArchiveMaxFileBytes is refused.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "evaluator/recipe.h"
#include "evaluator/results.h"

namespace weathergs::evaluator {

inline constexpr const char* kArchiveResultsFile = "results.json";
inline constexpr const char* kArchiveCurveFile = "curve.json";
inline constexpr const char* kArchiveRunFile = "run.json";
inline constexpr const char* kArchiveProvenanceFile = "provenance.json";
// A record is a few kB (results.json of 30 test views: ~9 kB); anything near this is not a record.
inline constexpr int64_t kArchiveMaxFileBytes = 256 * 1024;

struct ArchiveCell {
  std::string variant, method;
  int seed = 0;
  std::string dir(const std::string& suite_dir) const;  // <suite_dir>/<variant>/<method>/seed<N>
  std::string to_string() const;                         // "pool_rain weathergs seed0"
  bool operator<(const ArchiveCell& o) const;
};

// The CPU seconds a run cost, from its method_info: the training's train_cpu_seconds (or, in runs
// that do not record them, train_seconds x threads) plus (filter + detect + render seconds) x
// threads; a run that records no thread count counts as one thread.
double run_cpu_seconds(const Results& results);
// Whether a run records its training's CPU seconds (method_info.train_cpu_seconds).
bool records_cpu_seconds(const Results& results);

struct ArchiveAddOptions {
  std::string run_dir;    // a finished run of `reconstruct` (results.json, curve.json, model/run.json)
  std::string suite_dir;  // <root>/<suite>
  std::string variant;    // empty: the results' dataset name (generate names it <scene>_<weather>)
  bool replace = false;   // replace an archived run of another recipe (refused otherwise)
};
struct ArchiveAddResult {
  ArchiveCell cell;
  std::string dir;
  enum class Outcome { kAdded, kReplaced, kKept } outcome = Outcome::kAdded;
};
// Copies the run's records into its cell, atomically. A cell already holding a run of the same
// recipe is kept as it is (kKept; also for a run folder restored from the archive) unless `replace`; one of another recipe is refused (InputError
// naming both files and the first differing recipe key) unless `replace`. InputError when the run
// is incomplete, records no recipe or seed, or a record is larger than kArchiveMaxFileBytes.
ArchiveAddResult archive_add(const ArchiveAddOptions& options);

struct ArchivedRun {
  ArchiveCell cell;
  std::string dir;
  Results results;
  RecordedRecipe recipe;
};
// The run archived in `cell`, or nullopt when the cell holds none. InputError when its records are
// unreadable or record no recipe.
std::optional<ArchivedRun> read_archived_run(const std::string& suite_dir, const ArchiveCell& cell);
// Every run archived under suite_dir, in cell order.
std::vector<ArchivedRun> read_archive(const std::string& suite_dir);

// A suite's cells (benchmarks/results/<suite>/matrix.json; docs/archive.md, "The matrix"):
// {"format": "weathergs-archive-matrix", "version": 1, "suite", "description", "variants": [...],
//  "groups": [{"methods": [...], "seeds": [...], "variants": [...] (optional: a subset), "note"}],
//  "options": {"3dgs": {TrainOptions}, "nerf": {NerfOptions}} (what each backend's cells run with, as
//  reconstruct --train-options / --nerf-options files: a key left out keeps its default),
//  "estimates": {"source", "cpu_seconds": {method: seconds}}}
struct ArchiveMatrix {
  std::string suite, description;
  std::vector<ArchiveCell> cells;                        // in the file's order, each once
  std::map<std::string, Json> options;                   // backend ("3dgs", "nerf") -> its options file
  std::map<std::string, double> estimate_cpu_seconds;    // method -> a cell's CPU seconds, from the docs
  std::string estimate_source;
  std::vector<std::string> notes;
};
ArchiveMatrix read_archive_matrix(const std::string& path);

struct CellStatus {
  ArchiveCell cell;
  enum class State { kDone, kStale, kMissing } state = State::kMissing;
  std::string why;         // stale: the first differing recipe key; done: what was not checked
  double cpu_seconds = 0;  // archived runs: what it cost; missing and stale: what it is expected to cost
  bool estimated = false;  // the expectation comes from the matrix's estimates, not from done cells
};
struct ArchiveStatus {
  std::string suite;
  std::vector<CellStatus> cells;
  int done = 0, stale = 0, missing = 0;
  double spent_cpu_seconds = 0, left_cpu_seconds = 0;
  bool left_estimated = false;  // some of what is left comes from the matrix's estimates
  int estimated_cells = 0;      // how many cells' expectation does
  std::vector<std::string> notes;
};
// The recipe a run of `cell` would have now. Without the cell's dataset, the part every variant
// shares (recipe_across_datasets, no "dataset" key): then a run counts as done when its recipe
// agrees on that part, and says that its dataset was not checked.
using CurrentRecipe = std::function<Json(const ArchiveCell& cell)>;
// Notes also every archived run the matrix does not list.
ArchiveStatus archive_status(const std::string& suite_dir, const ArchiveMatrix& matrix, const CurrentRecipe& current);
std::string render_archive_status(const ArchiveStatus& status);

}  // namespace weathergs::evaluator
