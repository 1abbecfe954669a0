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

}  // namespace
}  // namespace weathergs::evaluator
