#include "evaluator/archive.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <set>
#include <sstream>

#include "core/atomic_file.h"

namespace weathergs::evaluator {

namespace fs = std::filesystem;

std::string ArchiveCell::dir(const std::string& suite_dir) const {
  return (fs::path(suite_dir) / variant / method / ("seed" + std::to_string(seed))).string();
}

std::string ArchiveCell::to_string() const { return variant + " " + method + " seed" + std::to_string(seed); }

bool ArchiveCell::operator<(const ArchiveCell& o) const {
  return std::tie(variant, method, seed) < std::tie(o.variant, o.method, o.seed);
}

bool records_cpu_seconds(const Results& r) {
  return r.method_info.contains("train_cpu_seconds") && r.method_info.at("train_cpu_seconds").is_number();
}

double run_cpu_seconds(const Results& r) {
  const Json& info = r.method_info;
  auto number = [&](const char* key) { return info.contains(key) && info.at(key).is_number() ? info.at(key).get<double>() : 0.0; };
  const int threads = info.contains("threads") && info.at("threads").is_number_integer() ? info.at("threads").get<int>() : 1;
  // The training's own CPU seconds where recorded: wall seconds times threads overstate a run that
  // shared its cores with other jobs.
  const double train = records_cpu_seconds(r) ? number("train_cpu_seconds") : number("train_seconds") * std::max(1, threads);
  return train + (number("filter_seconds") + number("detect_seconds") + number("render_seconds")) * std::max(1, threads);
}

namespace {

// The seed reconstruct records (method_info.seed).
int recorded_seed(const Results& r, const std::string& where) {
  const Json& info = r.method_info;
  if (!info.contains("seed") || !info.at("seed").is_number_integer())
    throw InputError(where + ":/method_info/seed", "missing: an archived run is a run of `weathergs reconstruct`, which records its seed");
  return info.at("seed").get<int>();
}

std::string utc_now() {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

std::string small_record(const fs::path& path) {
  if (!fs::is_regular_file(path)) throw InputError(path.string(), "missing: a finished run of `weathergs reconstruct` has it");
  if (int64_t(fs::file_size(path)) > kArchiveMaxFileBytes)
    throw InputError(path.string(), "is " + std::to_string(fs::file_size(path)) + " bytes, more than a record's " +
                                        std::to_string(kArchiveMaxFileBytes) + ": renders and models stay out of the archive");
  return read_file(path.string());
}

}  // namespace

std::optional<ArchivedRun> read_archived_run(const std::string& suite_dir, const ArchiveCell& cell) {
  const fs::path dir = cell.dir(suite_dir);
  const fs::path results = dir / kArchiveResultsFile;
  if (!fs::exists(results)) return std::nullopt;
  ArchivedRun run;
  run.cell = cell;
  run.dir = dir.string();
  run.results = read_results(results.string());
  const std::optional<RecordedRecipe> recipe = recorded_recipe(run.results, results.string());
  if (!recipe) throw InputError(results.string(), "records no recipe (method_info.recipe): not an archived run");
  run.recipe = *recipe;
  return run;
}

std::vector<ArchivedRun> read_archive(const std::string& suite_dir) {
  std::vector<ArchivedRun> out;
  if (!fs::is_directory(suite_dir)) return out;
  std::vector<ArchiveCell> cells;
  for (const auto& v : fs::directory_iterator(suite_dir)) {
    if (!v.is_directory()) continue;
    for (const auto& m : fs::directory_iterator(v.path())) {
      if (!m.is_directory()) continue;
      for (const auto& s : fs::directory_iterator(m.path())) {
        const std::string name = s.path().filename().string();
        if (!s.is_directory() || name.rfind("seed", 0) != 0 || name.size() == 4 ||
            name.find_first_not_of("0123456789", 4) != std::string::npos)
          continue;
        cells.push_back({v.path().filename().string(), m.path().filename().string(), std::stoi(name.substr(4))});
      }
    }
  }
  std::sort(cells.begin(), cells.end());
  for (const ArchiveCell& c : cells)
    if (std::optional<ArchivedRun> r = read_archived_run(suite_dir, c)) out.push_back(std::move(*r));
  return out;
}

ArchiveAddResult archive_add(const ArchiveAddOptions& o) {
  if (o.run_dir.empty()) throw InputError("archive add", "the run folder is empty");
  if (o.suite_dir.empty()) throw InputError("archive add", "the suite folder (<root>/<suite>) is empty");
  const fs::path run(o.run_dir);
  const std::string results_path = (run / kArchiveResultsFile).string();
  const std::string results_text = small_record(results_path);
  const Results results = read_results(results_path);
  const std::optional<RecordedRecipe> recipe = recorded_recipe(results, results_path);
  if (!recipe)
    throw InputError(results_path, "records no recipe (method_info.recipe): made before runs recorded one, it cannot be "
                                   "matched to a recipe later; re-run it");
  ArchiveAddResult out;
  out.cell = {o.variant.empty() ? results.dataset : o.variant, results.method, recorded_seed(results, results_path)};
  out.dir = out.cell.dir(o.suite_dir);
  if (const std::optional<ArchivedRun> held = read_archived_run(o.suite_dir, out.cell)) {
    if (held->recipe.fingerprint == recipe->fingerprint && !o.replace) {
      out.outcome = ArchiveAddResult::Outcome::kKept;
      return out;
    }
    if (held->recipe.fingerprint != recipe->fingerprint && !o.replace)
      throw InputError(results_path, "made with another recipe than the archived " +
                                         (fs::path(held->dir) / kArchiveResultsFile).string() + " (" +
                                         first_recipe_difference(recipe->recipe, held->recipe.recipe)->to_string() +
                                         "): pass --replace to replace it");
    out.outcome = ArchiveAddResult::Outcome::kReplaced;
  }
  const std::string curve = small_record(run / kArchiveCurveFile);
  const std::string run_record = small_record(run / "model" / kArchiveRunFile);
  const Json& info = results.method_info;
  const Json provenance{{"format", "weathergs-archive-run"},
                        {"version", 1},
                        {"added", utc_now()},
                        {"threads", info.contains("threads") ? info.at("threads") : Json()},
                        {"cpu_seconds", run_cpu_seconds(results)},
                        {"source", fs::absolute(run).lexically_normal().string()}};
  AtomicDirectory cell(out.dir);
  write_file_atomic((fs::path(cell.path()) / kArchiveResultsFile).string(), results_text);
  write_file_atomic((fs::path(cell.path()) / kArchiveCurveFile).string(), curve);
  write_file_atomic((fs::path(cell.path()) / kArchiveRunFile).string(), run_record);
  write_file_atomic((fs::path(cell.path()) / kArchiveProvenanceFile).string(), provenance.dump(2) + "\n");
  cell.commit();
  return out;
}

ArchiveMatrix read_archive_matrix(const std::string& path) {
  const JsonReader r = JsonReader::from_file(path);
  if (r.get<std::string>("format") != "weathergs-archive-matrix")
    throw InputError(r.where("format"), "expected \"weathergs-archive-matrix\"");
  if (r.get<int>("version") != 1) throw InputError(r.where("version"), "expected version 1");
  ArchiveMatrix m;
  m.suite = r.get<std::string>("suite");
  m.description = r.get_or<std::string>("description", "");
  const std::vector<std::string> variants = r.get<std::vector<std::string>>("variants");
  const JsonReader groups = r.child("groups");
  if (!groups.is_array()) throw InputError(groups.where(), "expected an array of {methods, seeds[, variants, note]}");
  std::set<ArchiveCell> seen;
  for (size_t i = 0; i < groups.size(); ++i) {
    const JsonReader g = groups.at(i);
    const std::vector<std::string> methods = g.get<std::vector<std::string>>("methods");
    const std::vector<int> seeds = g.get<std::vector<int>>("seeds");
    const std::vector<std::string> only = g.get_or<std::vector<std::string>>("variants", variants);
    for (const std::string& v : only)
      if (std::find(variants.begin(), variants.end(), v) == variants.end())
        throw InputError(g.where("variants"), "names " + v + ", which is not one of the suite's variants");
    if (const std::optional<std::string> note = g.get_optional<std::string>("note")) m.notes.push_back(*note);
    g.finish();
    for (const std::string& v : only)
      for (const std::string& method : methods)
        for (int seed : seeds) {
          const ArchiveCell c{v, method, seed};
          if (!seen.insert(c).second) throw InputError(g.where(), "lists " + c.to_string() + " twice");
          m.cells.push_back(c);
        }
  }
  if (r.has("options")) {
    const JsonReader f = r.child("options");
    for (const std::string& backend : f.keys()) {
      if (backend != "3dgs" && backend != "nerf") throw InputError(f.where(backend), "expected the backend 3dgs or nerf");
      const JsonReader b = f.child(backend);
      if (!b.is_object()) throw InputError(b.where(), "expected an object of options");
      m.options[backend] = b.value();
    }
  }
  if (r.has("estimates")) {
    const JsonReader e = r.child("estimates");
    m.estimate_source = e.get<std::string>("source");
    const JsonReader s = e.child("cpu_seconds");
    for (const std::string& method : s.keys()) m.estimate_cpu_seconds[method] = s.get_number(method, 0, 1e9);
    s.finish();
    e.finish();
  }
  r.finish();
  return m;
}

ArchiveStatus archive_status(const std::string& suite_dir, const ArchiveMatrix& matrix, const CurrentRecipe& current) {
  ArchiveStatus s;
  s.suite = matrix.suite;
  s.notes = matrix.notes;
  // method -> CPU seconds of its done cells: those that record their training's CPU seconds, and
  // those that do not (wall seconds x threads, an overstatement under load), the latter used only
  // while a method has none of the former.
  std::map<std::string, std::vector<double>> done_seconds, done_wall_seconds;
  for (const ArchiveCell& cell : matrix.cells) {
    CellStatus c;
    c.cell = cell;
    if (const std::optional<ArchivedRun> run = read_archived_run(suite_dir, cell)) {
      c.cpu_seconds = run_cpu_seconds(run->results);
      const Json now = current(cell);
      // Without the dataset, what it makes of the recipe cannot be known: the rest is compared.
      const bool whole = now.contains("dataset");
      const std::optional<RecipeDifference> d =
          whole ? first_recipe_difference(run->recipe.recipe, now)
                : first_recipe_difference(recipe_across_datasets(run->recipe.recipe), now);
      if (d) {
        c.state = CellStatus::State::kStale;
        c.why = d->to_string();
      } else {
        c.state = CellStatus::State::kDone;
        if (!whole) c.why = "dataset not checked";
        if (!records_cpu_seconds(run->results))
          c.why += std::string(c.why.empty() ? "" : "; ") + "cost from wall seconds x threads: no CPU seconds recorded";
        (records_cpu_seconds(run->results) ? done_seconds : done_wall_seconds)[cell.method].push_back(c.cpu_seconds);
        s.spent_cpu_seconds += c.cpu_seconds;
      }
    }
    s.cells.push_back(c);
  }
  for (CellStatus& c : s.cells) {
    if (c.state == CellStatus::State::kDone) {
      ++s.done;
      continue;
    }
    ++(c.state == CellStatus::State::kStale ? s.stale : s.missing);
    // A stale run's own cost is the best guess of its re-run's; else the method's done cells, else the
    // matrix's estimate.
    if (c.state == CellStatus::State::kMissing || c.cpu_seconds <= 0) {
      const std::vector<double>* done = nullptr;
      if (const auto it = done_seconds.find(c.cell.method); it != done_seconds.end()) done = &it->second;
      else if (const auto jt = done_wall_seconds.find(c.cell.method); jt != done_wall_seconds.end()) done = &jt->second;
      if (done) {
        double sum = 0;
        for (double x : *done) sum += x;
        c.cpu_seconds = sum / double(done->size());
      } else if (const auto e = matrix.estimate_cpu_seconds.find(c.cell.method); e != matrix.estimate_cpu_seconds.end()) {
        c.cpu_seconds = e->second;
        c.estimated = true;
      } else {
        c.cpu_seconds = 0;
        c.estimated = true;
      }
    }
    s.left_cpu_seconds += c.cpu_seconds;
    s.left_estimated = s.left_estimated || c.estimated;
    s.estimated_cells += c.estimated;
  }
  if (s.left_estimated) s.notes.push_back("Estimates: " + (matrix.estimate_source.empty() ? "none given" : matrix.estimate_source));
  const std::set<ArchiveCell> listed(matrix.cells.begin(), matrix.cells.end());
  for (const ArchivedRun& run : read_archive(suite_dir))
    if (!listed.count(run.cell)) s.notes.push_back("archived but not in the matrix: " + run.cell.to_string());
  return s;
}

std::string render_archive_status(const ArchiveStatus& s) {
  std::ostringstream o;
  auto hours = [](double seconds) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.2f", seconds / 3600);
    return std::string(buf);
  };
  o << "suite " << s.suite << ": " << s.cells.size() << " cells\n";
  for (const CellStatus& c : s.cells) {
    const char* state = c.state == CellStatus::State::kDone ? "done" : c.state == CellStatus::State::kStale ? "stale" : "missing";
    o << "  " << state << std::string(8 - std::string(state).size(), ' ') << c.cell.to_string();
    if (c.state == CellStatus::State::kDone) o << "  " << hours(c.cpu_seconds) << " CPU-h";
    else o << "  ~" << hours(c.cpu_seconds) << " CPU-h" << (c.estimated ? " (estimate)" : "");
    if (!c.why.empty()) o << "  (" << c.why << ")";
    o << "\n";
  }
  o << "done " << s.done << ", stale " << s.stale << ", missing " << s.missing << " of " << s.cells.size() << "\n";
  o << "CPU-hours: spent " << hours(s.spent_cpu_seconds) << ", left ~" << hours(s.left_cpu_seconds)
    << (s.left_estimated ? " (" + std::to_string(s.estimated_cells) + " of the " + std::to_string(s.stale + s.missing) +
                               " cells left from the matrix's estimates)"
                         : "")
    << "\n";
  for (const std::string& n : s.notes) o << "note: " << n << "\n";
  return o.str();
}

}  // namespace weathergs::evaluator
