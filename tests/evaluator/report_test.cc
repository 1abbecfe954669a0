// `weathergs report` without a browser: the page's embedded data (data.js) holds exactly the numbers
// of the results files, every image it names exists, and bad suites are refused. The page itself is
// checked in headless Chromium by `make interop` (interop/report_check.mjs).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset_identity.h"
#include "core/json_reader.h"
#include "evaluator/recipe.h"
#include "evaluator/report.h"
#include "evaluator/results.h"
#include "tests/core/test_util.h"

namespace weathergs::evaluator {
namespace {

namespace fs = std::filesystem;
using testing::run_command;
using testing::TempDir;

const std::string kBin = WEATHERGS_BINARY;

// A suite folder as the workflow writes it, from the example benchmark: data/<variant>/ and
// runs/<variant>/<method>/seed<S>/ with renders/test/ and results.json (scored by the binary).
std::string make_suite(const TempDir& tmp) {
  const std::string ex = tmp / "ex", suite = tmp / "suite";
  auto r = run_command(kBin + " --quiet example -o " + ex);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  for (const char* variant : {"park_rain", "park_snow"}) {
    copy_tree(ex + "/datasets/" + variant, suite + "/data/" + variant);
    int seed = 0;
    for (const char* method : {"box-blur", "noise", "noise"}) {  // noise twice: two seeds of one method
      const std::string run = suite + "/runs/" + variant + "/" + method + "/seed" + std::to_string(seed++);
      copy_tree(ex + "/renders/" + method + "/" + variant, run + "/renders/test");
      r = run_command(kBin + " --quiet evaluate --gt " + suite + "/data/" + variant + " --renders " + run +
                      "/renders/test -o " + run + "/results.json");
      EXPECT_EQ(r.exit_code, 0) << r.output;
    }
  }
  return suite;
}

Json read_data_js(const std::string& report) {
  const std::string js = read_file(report + "/data.js");
  const std::string prefix = "window.WEATHERGS_REPORT = ";
  EXPECT_EQ(js.rfind(prefix, 0), 0u);
  return Json::parse(js.substr(prefix.size(), js.rfind(';') - prefix.size()));
}

TEST(Report, EmbeddedDataEqualsTheResultsFiles) {
  TempDir tmp;
  const std::string suite = make_suite(tmp), report = tmp / "report";
  auto r = run_command(kBin + " --quiet report " + suite + " -o " + report);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(report + "/index.html"), std::string::npos) << r.output;
  for (const char* f : {"index.html", "report.css", "report.js", "data.js"}) EXPECT_TRUE(fs::exists(report + "/" + f)) << f;
  const Json d = read_data_js(report);
  EXPECT_EQ(d.at("format"), "weathergs-report");
  ASSERT_EQ(d.at("variants").size(), 2u);
  int checked = 0;
  for (const Json& v : d.at("variants")) {
    // Columns: the input, every run, the truth.
    ASSERT_EQ(v.at("columns").size(), 5u) << v.at("columns").dump();
    EXPECT_EQ(v.at("columns").front().at("id"), "input");
    EXPECT_EQ(v.at("columns").back().at("id"), "gt");
    for (const Json& view : v.at("views")) {
      for (const auto& [column, cell] : view.at("cells").items()) {
        for (const char* k : {"thumb", "full", "diff"})
          if (cell.contains(k)) {
            EXPECT_TRUE(fs::exists(report + "/" + cell.at(k).get<std::string>())) << cell.at(k);
          }
        if (column == "input" || column == "gt") continue;
        // The per-view numbers are the results file's, bit for bit.
        const std::string method = column.substr(0, column.find('/')), seed = column.substr(column.find('/') + 1);
        const Json res = read_json_file(suite + "/runs/" + v.at("name").get<std::string>() + "/" + method + "/" + seed + "/results.json");
        const Json& truth = res.at("per_view").at(view.at("name").get<std::string>());
        for (const char* m : {"psnr", "ssim", "lpips"}) {
          EXPECT_EQ(cell.at("metrics").at(m), truth.at(m)) << column << " " << m;
          ++checked;
        }
      }
    }
  }
  EXPECT_EQ(checked, 2 * 2 * 3 * 3);  // variants x test views x runs x metrics
  // The leaderboard: one table per weather, the two seeds of `noise` as mean ± interval.
  bool interval = false;
  for (const Json& t : d.at("tables"))
    for (const Json& row : t.at("rows"))
      for (const auto& [key, cell] : row.at("cells").items())
        if (row.at("method") == "noise" && cell.contains("ci95")) interval = true;
  EXPECT_TRUE(interval);
  EXPECT_FALSE(d.at("provenance").at("commit").get<std::string>().empty());
  ASSERT_EQ(d.at("provenance").at("datasets").size(), 2u);
  // Each dataset's identity, and each run's (short): the runs were scored on the data shown.
  for (const Json& ds : d.at("provenance").at("datasets")) {
    const std::string id = compute_dataset_identity(suite + "/data/" + ds.at("name").get<std::string>()).sha256;
    EXPECT_EQ(ds.at("dataset_identity"), id);
    for (const Json& run : d.at("runs"))
      if (run.at("variant") == ds.at("name")) {
        EXPECT_EQ(run.at("dataset_identity"), id.substr(0, 12));
        EXPECT_EQ(run.at("other_data"), false);
      }
  }
  // A report of this size stays small.
  uintmax_t bytes = 0;
  for (const auto& e : fs::recursive_directory_iterator(report))
    if (e.is_regular_file()) bytes += e.file_size();
  EXPECT_LT(bytes, 5u << 20);
}

TEST(Report, ConfidenceIntervalsUseStudentsT) {
  EXPECT_DOUBLE_EQ(confidence_half_width_95(1, 1.0), 0.0);
  EXPECT_NEAR(confidence_half_width_95(2, 1.0), 12.706 / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(confidence_half_width_95(3, 0.5), 4.303 * 0.5 / std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(confidence_half_width_95(100, 1.0), 1.96 / 10, 1e-12);
}

TEST(Report, BadSuitesAreRefusedAndLeaveNothing) {
  TempDir tmp;
  auto r = run_command(kBin + " --quiet report " + (tmp / "none") + " -o " + (tmp / "rep"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("runs"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp / "rep"));
  const std::string suite = make_suite(tmp);
  fs::remove_all(suite + "/data/park_snow");
  r = run_command(kBin + " --quiet report " + suite + " -o " + (tmp / "rep"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("park_snow"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp / "rep"));
}

void flip_byte(const std::string& path) {
  std::string bytes = read_file(path);
  bytes[bytes.size() / 2] = char(~bytes[bytes.size() / 2]);
  write_file_atomic(path, bytes);
}

// A run scored on other data than the page shows beside it, or than its variant's other runs, is
// refused (leaving nothing) unless --allow-mixed-data, which marks it.
TEST(Report, RunsOnOtherDataAreRefusedOrMarked) {
  TempDir tmp;
  const std::string suite = make_suite(tmp), report = tmp / "report";
  const std::string make_report = kBin + " --quiet report " + suite + " -o " + report;
  // data/park_snow changed after its runs were scored.
  flip_byte(suite + "/data/park_snow/images/000.png");
  auto r = run_command(make_report);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("runs/park_snow/"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("data/park_snow"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--allow-mixed-data"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(report));
  flip_byte(suite + "/data/park_snow/images/000.png");  // back as it was
  // One seed of park_rain's noise scored on a regenerated copy: two datasets in one variant.
  const std::string other = tmp / "other";
  copy_tree(suite + "/data/park_rain", other);
  flip_byte(other + "/images/000.png");
  Json dj = read_json_file(other + "/dataset.json");
  dj["identity"] = compute_dataset_identity(other).to_json(true);
  write_file_atomic(other + "/dataset.json", dj.dump(2));
  const std::string run = suite + "/runs/park_rain/noise/seed2";
  r = run_command(kBin + " --quiet evaluate --gt " + other + " --renders " + run + "/renders/test -o " + run + "/results.json");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_command(make_report);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("seed2/results.json"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(report));
  r = run_command(make_report + " --allow-mixed-data");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json d = read_data_js(report);
  const std::string other_id = compute_dataset_identity(other).sha256;
  int marked_runs = 0;
  for (const Json& run_entry : d.at("runs")) {
    const bool odd = run_entry.at("variant") == "park_rain" && run_entry.at("seed") == 2;
    EXPECT_EQ(run_entry.at("other_data"), odd) << run_entry.dump();
    if (odd) EXPECT_EQ(run_entry.at("dataset_identity"), other_id.substr(0, 12));
    marked_runs += odd;
  }
  EXPECT_EQ(marked_runs, 1);
  bool marked_cell = false, noted = false;
  for (const Json& t : d.at("tables")) {
    noted = noted || t.at("note").get<std::string>().find(other_id.substr(0, 12)) != std::string::npos;
    for (const Json& row : t.at("rows"))
      for (const auto& [key, cell] : row.at("cells").items())
        if (cell.at("text").get<std::string>().find("†") != std::string::npos) {
          EXPECT_EQ(row.at("method"), "noise") << key;
          marked_cell = true;
        }
  }
  EXPECT_TRUE(marked_cell);
  EXPECT_TRUE(noted);
  EXPECT_NE(d.at("provenance").at("command").get<std::string>().find("--allow-mixed-data"), std::string::npos);
}

// Records a recipe in a run's results.json, as reconstruct does.
void set_recipe(const std::string& results, int densify_until) {
  const Json recipe{{"method", "noise"}, {"backend", "3dgs"}, {"numerics", "3dgs-numerics-1"},
                    {"options", {{"densify_until", densify_until}}}};
  Json j = read_json_file(results);
  j["method_info"][kRecipeKey] = recipe;
  j["method_info"][kRecipeFingerprintKey] = recipe_fingerprint(recipe);
  write_file_atomic(results, j.dump(2));
}

// A run restored from the results archive has no renders: the page lists it without images and keeps
// its numbers; runs of one method with other recipes are refused unless --allow-mixed-recipes.
TEST(Report, ArchivedRunsWithoutRendersAndMixedRecipes) {
  TempDir tmp;
  const std::string suite = make_suite(tmp), report = tmp / "report";
  const std::string make_report = kBin + " --quiet report " + suite + " -o " + report;
  fs::remove_all(suite + "/runs/park_snow/box-blur/seed0/renders");
  for (const char* v : {"park_rain", "park_snow"})
    for (int seed : {1, 2}) set_recipe(suite + "/runs/" + v + "/noise/seed" + std::to_string(seed) + "/results.json", 15000);
  auto r = run_command(make_report);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  Json d = read_data_js(report);
  for (const Json& v : d.at("variants")) {
    const bool snow = v.at("name") == "park_snow";
    EXPECT_EQ(v.at("columns").size(), snow ? 4u : 5u) << v.at("columns").dump();
    EXPECT_EQ(v.at("without_renders"), snow ? Json::array({"box-blur (seed 0)"}) : Json::array());
  }
  int archived = 0;
  for (const Json& run : d.at("runs")) archived += run.at("archived").get<bool>();
  EXPECT_EQ(archived, 1);
  EXPECT_NE(d.at("tables").dump().find("box-blur"), std::string::npos);  // its numbers stay in the tables
  // A results archive's suite folder (<variant>/<method>/seed<S>/, records only, no data/): the
  // tables, the runs and their datasets' identities, no variant pages.
  const std::string archive = tmp / "archive/quick";
  for (const auto& e : fs::recursive_directory_iterator(suite + "/runs"))
    if (e.path().filename() == "results.json") {
      const fs::path cell = fs::path(archive) / fs::relative(e.path().parent_path(), suite + "/runs");
      fs::create_directories(cell);
      fs::copy_file(e.path(), cell / "results.json");
    }
  r = run_command(kBin + " --quiet report " + archive + " -o " + (tmp / "archive_report"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json a = read_data_js(tmp / "archive_report");
  EXPECT_TRUE(a.at("variants").empty());
  EXPECT_EQ(a.at("runs").size(), 6u);
  EXPECT_EQ(a.at("provenance").at("datasets").size(), 2u);
  ASSERT_EQ(a.at("tables").size(), d.at("tables").size());
  for (size_t t = 0; t < a.at("tables").size(); ++t)  // the same numbers, cell by cell (links aside)
    for (size_t row = 0; row < a.at("tables")[t].at("rows").size(); ++row)
      for (const auto& [key, cell] : a.at("tables")[t].at("rows")[row].at("cells").items())
        EXPECT_EQ(cell.at("text"), d.at("tables")[t].at("rows")[row].at("cells").at(key).at("text")) << key;
  const std::string link = a.at("tables")[0].at("rows")[0].at("cells").at("park.psnr").at("link");
  EXPECT_TRUE(fs::is_directory(tmp / ("archive_report/" + link))) << link;
  // One seed of noise with another option: refused, naming it; marked when allowed.
  set_recipe(suite + "/runs/park_rain/noise/seed2/results.json", 7000);
  r = run_command(make_report);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("park_rain/noise/seed2/results.json"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("options/densify_until: 7000 vs 15000"), std::string::npos) << r.output;
  r = run_command(make_report + " --allow-mixed-recipes");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  d = read_data_js(report);
  for (const Json& run : d.at("runs"))
    EXPECT_EQ(run.at("other_recipe"), run.at("variant") == "park_rain" && run.at("seed") == 2) << run.dump();
  EXPECT_NE(d.at("tables").dump().find("‡"), std::string::npos);
}

// A results archive's suite folder of copies of the suite's results.json: the cells given as
// "<variant>/<method>/seed<S>" (the archive's own variant may differ from the run it copies).
void archive_copies(const std::string& suite, const std::string& archive,
                    const std::vector<std::pair<std::string, std::string>>& cells) {
  for (const auto& [from, to] : cells) {
    fs::create_directories(archive + "/" + to);
    fs::copy_file(suite + "/runs/" + from + "/results.json", archive + "/" + to + "/results.json");
  }
}

// --converged ARCHIVE: the archive's runs of the suite's variants in tables of their own (never mixed
// into the suite's: those stay byte for byte what they are without it), how many cells of its matrix
// hold a run, whether they were scored on the suite's datasets; --note at the top of the page.
TEST(Report, ConvergedTablesFromTheArchiveBesideTheSuite) {
  TempDir tmp;
  const std::string suite = make_suite(tmp), archive = tmp / "results/quick";
  auto r = run_command(kBin + " --quiet report " + suite + " -o " + (tmp / "plain"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json plain = read_data_js(tmp / "plain");
  EXPECT_FALSE(plain.contains("converged") || plain.contains("note"));
  // Two runs of park_rain, and one of a variant the suite does not have (not shown, not even read).
  archive_copies(suite, archive, {{"park_rain/box-blur/seed0", "park_rain/box-blur/seed0"},
                                  {"park_rain/noise/seed1", "park_rain/noise/seed0"},
                                  {"park_snow/noise/seed1", "yard_snow/noise/seed0"}});
  write_file_atomic(archive + "/yard_snow/noise/seed0/results.json", "not json: never read");
  write_file_atomic(archive + "/matrix.json",
                    Json{{"format", "weathergs-archive-matrix"}, {"version", 1}, {"suite", "quick"},
                         {"variants", {"park_rain", "park_snow", "yard_snow"}},
                         {"groups", {{{"methods", {"box-blur", "noise"}}, {"seeds", {0, 1}}}}}}.dump());
  const std::string note = "A smoke run at 150 iterations, not converged: the converged tables are in the archive.";
  const std::string report = tmp / "report";
  r = run_command(kBin + " --quiet report " + suite + " -o " + report + " --converged " + archive + " --note '" + note + "'");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("converged (archive): 2 runs"), std::string::npos) << r.output;
  const Json d = read_data_js(report);
  EXPECT_EQ(d.at("note"), note);
  EXPECT_EQ(d.at("tables"), plain.at("tables"));  // the suite's own rows are untouched
  EXPECT_EQ(d.at("runs").size(), plain.at("runs").size());
  const Json& c = d.at("converged");
  EXPECT_EQ(c.at("path"), archive);
  EXPECT_EQ(c.at("runs"), 2);
  EXPECT_EQ(c.at("variants"), Json::array({"park_rain", "park_snow"}));
  // 3 variants x 2 methods x 2 seeds; on park_rain and park_snow 8, of which box-blur seed0 and noise
  // seed0 of park_rain hold a run.
  EXPECT_EQ(c.at("matrix"), (Json{{"cells", 12}, {"archived", 3}, {"variant_cells", 8}, {"variant_archived", 2}}));
  EXPECT_NE(c.at("lines").dump().find("3 of 12 cells archived; 2 of the 8 on park_rain, park_snow"), std::string::npos)
      << c.at("lines").dump();
  EXPECT_NE(c.at("lines").dump().find("the same datasets as this suite's: park_rain"), std::string::npos)
      << c.at("lines").dump();
  EXPECT_NE(c.at("lines").dump().find("on park_rain: 2 runs of 2 methods (none yet on park_snow)"), std::string::npos)
      << c.at("lines").dump();
  EXPECT_FALSE(c.contains("message"));
  // One table (rain), the same layout; box-blur's one run is the suite's, cell for cell; noise's one
  // archived run is not averaged with the suite's two.
  ASSERT_EQ(c.at("tables").size(), 1u);
  const Json& t = c.at("tables")[0];
  EXPECT_EQ(t.at("id"), "converged-table-1");
  const Json* suite_rain = nullptr;
  // The same weather's table of the suite (its numeral may differ: the suite has snow too).
  const auto weather_of = [](const Json& table) {
    const std::string title = table.at("title");
    return title.substr(title.find(": ") + 2);
  };
  for (const Json& st : d.at("tables"))
    if (st.at("title").get<std::string>().rfind("Table", 0) == 0 && st.at("title").get<std::string>().find(": ") != std::string::npos &&
        weather_of(st) == weather_of(t))
      suite_rain = &st;
  ASSERT_NE(suite_rain, nullptr) << t.at("title");
  EXPECT_EQ(t.at("columns"), suite_rain->at("columns"));
  ASSERT_EQ(t.at("rows").size(), 2u);
  for (const Json& row : t.at("rows")) {
    const Json& cells = row.at("cells");
    if (row.at("method") == "box-blur") {
      for (const Json& srow : suite_rain->at("rows"))
        if (srow.at("method") == "box-blur") EXPECT_EQ(cells.at("park.psnr").at("text"), srow.at("cells").at("park.psnr").at("text"));
    } else {
      EXPECT_EQ(cells.at("park.psnr").at("n"), 1);
      const Results seed1 = read_results(suite + "/runs/park_rain/noise/seed1/results.json");
      EXPECT_EQ(cells.at("park.psnr").at("value").get<double>(), seed1.metrics.psnr);
    }
    const std::string link = cells.at("park.psnr").at("link");  // into the archive, relative
    EXPECT_TRUE(fs::exists(report + "/" + link + "seed0/results.json")) << link;
  }
  EXPECT_EQ(c.at("cost").at("rows").size(), 2u);
  EXPECT_NE(d.at("provenance").at("command").get<std::string>().find("--converged " + archive + " --note '"), std::string::npos);

  // An archive that holds no run of these variants yet: said plainly, no table.
  const std::string fresh = tmp / "fresh/quick";
  archive_copies(suite, fresh, {{"park_snow/noise/seed1", "yard_snow/noise/seed0"}});
  fs::copy_file(archive + "/matrix.json", fresh + "/matrix.json");
  r = run_command(kBin + " --quiet report " + suite + " -o " + report + " --converged " + fresh);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json e = read_data_js(report).at("converged");
  EXPECT_EQ(e.at("runs"), 0);
  EXPECT_TRUE(e.at("tables").empty());
  EXPECT_EQ(e.at("message"), "The results archive " + fresh + " holds no run of park_rain, park_snow yet: no converged tables to show.");
  EXPECT_EQ(e.at("matrix").at("variant_archived"), 0);
  EXPECT_EQ(e.at("matrix").at("archived"), 1);

  // Refused before anything is written: a missing folder, and a suite folder instead of an archive's.
  fs::remove_all(report);
  for (const std::string& bad : {std::string(tmp / "none"), suite}) {
    r = run_command(kBin + " --quiet report " + suite + " -o " + report + " --converged " + bad);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(bad), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(report));
  }
}

}  // namespace
}  // namespace weathergs::evaluator
