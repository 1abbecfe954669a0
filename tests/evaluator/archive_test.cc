// The results archive (evaluator/archive.h): a run's records go into its cell, a cell of the same
// recipe is kept, one of another recipe is refused unless replaced, renders and models stay out; the
// matrix and the status (done, stale naming the key, missing; CPU-hours spent and left). Hand-made
// run folders, no training (~0.1 s).
#include <gtest/gtest.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "evaluator/archive.h"
#include "tests/core/test_util.h"

namespace weathergs::evaluator {
namespace {

namespace fs = std::filesystem;
using weathergs::testing::TempDir;

Json recipe(const std::string& method, int densify_until = 15000, const std::string& dataset = "d1") {
  return {{"method", method},
          {"backend", "3dgs"},
          {"numerics", "3dgs-numerics-1"},
          {"options", {{"densify_until", densify_until}}},
          {"run_length", {{"iterations", 7000}}},
          {"points", "dataset"},
          {"dataset", dataset},
          {"weights", Json::object()},
          {"scoring", {{"lpips", "alex_v0.1"}}}};
}

// A finished run folder as reconstruct leaves it (results.json, curve.json, model/run.json).
std::string make_run(const TempDir& tmp, const std::string& name, const std::string& dataset, const std::string& method,
                     int seed, const Json& r, double train_seconds = 100, int threads = 2) {
  Results res;
  res.method = method;
  res.dataset = dataset;
  res.scene = "pool";
  res.weather = "rain";
  res.metrics = {25.0, 0.8, 0.2};
  res.per_view = {{"000", res.metrics}};
  res.method_info = {{"seed", seed},       {"train_seconds", train_seconds}, {"render_seconds", 2.0},
                     {"threads", threads}, {kRecipeKey, r},                  {kRecipeFingerprintKey, recipe_fingerprint(r)}};
  const std::string dir = tmp / name;
  fs::create_directories(dir + "/model");
  write_results(dir + "/results.json", res);
  write_file_atomic(dir + "/curve.json", R"({"format": "weathergs-curve", "points": []})");
  write_file_atomic(dir + "/model/run.json", R"({"format": "weathergs-3dgs-run"})");
  write_file_atomic(dir + "/model/point_cloud.ply", std::string(300000, 'x'));  // a model: never archived
  return dir;
}

TEST(ArchiveTest, AddKeepsTheSameRecipeRefusesAnotherUnlessReplacedAndKeepsOnlyRecords) {
  TempDir tmp;
  const std::string suite = tmp / "results/quick";
  const std::string run = make_run(tmp, "run", "pool_rain", "3dgs", 1, recipe("3dgs"));
  ArchiveAddOptions o;
  o.run_dir = run;
  o.suite_dir = suite;
  const ArchiveAddResult a = archive_add(o);
  EXPECT_EQ(a.outcome, ArchiveAddResult::Outcome::kAdded);
  EXPECT_EQ(a.dir, suite + "/pool_rain/3dgs/seed1");
  std::set<std::string> files;
  for (const auto& e : fs::directory_iterator(a.dir)) files.insert(e.path().filename().string());
  EXPECT_EQ(files, (std::set<std::string>{"results.json", "curve.json", "run.json", "provenance.json"}));
  EXPECT_EQ(read_file(a.dir + "/results.json"), read_file(run + "/results.json"));  // byte for byte
  const Json prov = read_json_file(a.dir + "/provenance.json");
  EXPECT_DOUBLE_EQ(prov.at("cpu_seconds").get<double>(), (100 + 2) * 2);
  EXPECT_EQ(prov.at("threads"), 2);
  // The same recipe again: kept as it is.
  EXPECT_EQ(archive_add(o).outcome, ArchiveAddResult::Outcome::kKept);
  // Another recipe of the same cell: refused, naming the key; --replace replaces it.
  const std::string other = make_run(tmp, "other", "pool_rain", "3dgs", 1, recipe("3dgs", 9000));
  o.run_dir = other;
  try {
    archive_add(o);
    ADD_FAILURE() << "another recipe was archived over the cell";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("options/densify_until: 9000 vs 15000"), std::string::npos) << e.what();
  }
  o.replace = true;
  EXPECT_EQ(archive_add(o).outcome, ArchiveAddResult::Outcome::kReplaced);
  EXPECT_EQ(read_archived_run(suite, {"pool_rain", "3dgs", 1})->recipe.recipe.at("options").at("densify_until"), 9000);
  // A run without a recipe, and a record the size of a render: refused.
  const std::string old = make_run(tmp, "old", "pool_rain", "oracle", 0, recipe("oracle"));
  Json j = read_json_file(old + "/results.json");
  j["method_info"].erase(kRecipeKey);
  j["method_info"].erase(kRecipeFingerprintKey);
  write_file_atomic(old + "/results.json", j.dump());
  o.run_dir = old;
  EXPECT_THROW(archive_add(o), InputError);
  const std::string big = make_run(tmp, "big", "pool_rain", "oracle", 0, recipe("oracle"));
  write_file_atomic(big + "/curve.json", std::string(kArchiveMaxFileBytes + 1, ' '));
  o.run_dir = big;
  EXPECT_THROW(archive_add(o), InputError);
  EXPECT_FALSE(fs::exists(suite + "/pool_rain/oracle"));  // nothing half-written
}

TEST(ArchiveTest, StatusSaysDoneStaleOrMissingWithTheCpuHours) {
  TempDir tmp;
  const std::string suite = tmp / "results/quick";
  write_file_atomic(tmp / "matrix.json", R"({
    "format": "weathergs-archive-matrix", "version": 1, "suite": "quick",
    "variants": ["pool_rain", "pool_snow"],
    "groups": [{"methods": ["3dgs"], "seeds": [0, 1]},
               {"methods": ["oracle"], "seeds": [0], "variants": ["pool_rain"], "note": "oracle on rain only"},
               {"methods": ["nerf"], "seeds": [0]}],
    "options": {"3dgs": {}, "nerf": {"iterations": 3000}},
    "estimates": {"source": "docs/schedules.md", "cpu_seconds": {"nerf": 1800}}})");
  const ArchiveMatrix m = read_archive_matrix(tmp / "matrix.json");
  ASSERT_EQ(m.cells.size(), 4u + 1u + 2u);
  EXPECT_EQ(m.options.at("nerf").at("iterations"), 3000);
  for (const auto& [name, seed, dens] : {std::tuple<const char*, int, int>{"a", 0, 15000}, {"b", 1, 9000}}) {
    ArchiveAddOptions o;
    o.run_dir = make_run(tmp, name, "pool_rain", "3dgs", seed, recipe("3dgs", dens), 3600, 1);
    o.suite_dir = suite;
    archive_add(o);
  }
  // The current recipe of every cell: densify_until 15000; without a dataset for pool_snow.
  const ArchiveStatus s = archive_status(suite, m, [](const ArchiveCell& c) {
    const Json r = recipe(c.method);
    return c.variant == "pool_rain" ? r : recipe_across_datasets(r);
  });
  EXPECT_EQ(s.done, 1);
  EXPECT_EQ(s.stale, 1);
  EXPECT_EQ(s.missing, 5);
  EXPECT_EQ(s.cells[1].state, CellStatus::State::kStale);
  EXPECT_EQ(s.cells[1].why, "options/densify_until: 9000 vs 15000");
  EXPECT_DOUBLE_EQ(s.spent_cpu_seconds, 3602);
  // Left: the stale run's own cost, 3dgs on snow at the done cell's mean (twice), the oracle with
  // no estimate (0, said), nerf twice at the matrix's estimate.
  EXPECT_DOUBLE_EQ(s.left_cpu_seconds, 3602 + 2 * 3602 + 0 + 2 * 1800);
  EXPECT_TRUE(s.left_estimated);
  const std::string text = render_archive_status(s);
  EXPECT_NE(text.find("stale   pool_rain 3dgs seed1"), std::string::npos) << text;
  EXPECT_NE(text.find("missing pool_snow nerf seed0  ~0.50 CPU-h (estimate)"), std::string::npos) << text;
  EXPECT_NE(text.find("done 1, stale 1, missing 5 of 7"), std::string::npos) << text;
  EXPECT_NE(text.find("note: oracle on rain only"), std::string::npos) << text;
  // A run archived outside the matrix is noted.
  ArchiveAddOptions extra;
  extra.run_dir = make_run(tmp, "extra", "yard_rain", "3dgs", 0, recipe("3dgs"));
  extra.suite_dir = suite;
  archive_add(extra);
  const std::string with_extra = render_archive_status(archive_status(suite, m, [](const ArchiveCell& c) { return recipe(c.method); }));
  EXPECT_NE(with_extra.find("note: archived but not in the matrix: yard_rain 3dgs seed0"), std::string::npos) << with_extra;
  // A done cell whose dataset could not be checked says so.
  const ArchiveStatus unchecked = archive_status(suite, m, [](const ArchiveCell& c) { return recipe_across_datasets(recipe(c.method)); });
  EXPECT_EQ(unchecked.cells[0].state, CellStatus::State::kDone);
  EXPECT_EQ(unchecked.cells[0].why, "dataset not checked; cost from wall seconds x threads: no CPU seconds recorded");
  // A matrix naming a variant it does not list, or a cell twice: refused.
  write_file_atomic(tmp / "bad.json", R"({"format": "weathergs-archive-matrix", "version": 1, "suite": "q",
    "variants": ["pool_rain"], "groups": [{"methods": ["3dgs"], "seeds": [0], "variants": ["pool_snow"]}]})");
  EXPECT_THROW(read_archive_matrix(tmp / "bad.json"), InputError);
  write_file_atomic(tmp / "twice.json", R"({"format": "weathergs-archive-matrix", "version": 1, "suite": "q",
    "variants": ["pool_rain"], "groups": [{"methods": ["3dgs"], "seeds": [0]}, {"methods": ["3dgs"], "seeds": [0]}]})");
  EXPECT_THROW(read_archive_matrix(tmp / "twice.json"), InputError);
}

// The cost left is guessed from the done cells that record their training's CPU seconds, not from
// those whose wall seconds (x threads) stand in for them, once a method has any of the former.
TEST(ArchiveTest, StatusPrefersCellsThatRecordCpuSeconds) {
  TempDir tmp;
  const std::string suite = tmp / "results/quick";
  write_file_atomic(tmp / "matrix.json", R"({"format": "weathergs-archive-matrix", "version": 1, "suite": "quick",
    "variants": ["pool_rain"], "groups": [{"methods": ["3dgs"], "seeds": [0, 1, 2]}]})");
  const ArchiveMatrix m = read_archive_matrix(tmp / "matrix.json");
  for (int seed : {0, 1}) {
    const std::string run = make_run(tmp, "run" + std::to_string(seed), "pool_rain", "3dgs", seed, recipe("3dgs"), 3600, 1);
    if (seed == 1) {  // 3600 s on the clock, 600 of them its own CPU's
      Results r = read_results(run + "/results.json");
      r.method_info["train_cpu_seconds"] = 600.0;
      write_results(run + "/results.json", r);
    }
    ArchiveAddOptions o;
    o.run_dir = run;
    o.suite_dir = suite;
    archive_add(o);
  }
  const ArchiveStatus s = archive_status(suite, m, [](const ArchiveCell& c) { return recipe(c.method); });
  ASSERT_EQ(s.done, 2);
  EXPECT_EQ(s.cells[0].why, "cost from wall seconds x threads: no CPU seconds recorded");
  EXPECT_EQ(s.cells[1].why, "");
  EXPECT_DOUBLE_EQ(s.spent_cpu_seconds, 3602 + 602);
  EXPECT_DOUBLE_EQ(s.left_cpu_seconds, 602);  // seed 2, at the CPU-recording cell's cost
  EXPECT_FALSE(s.left_estimated);
}

// A run's cost is its training's CPU seconds where it records them (a one-thread run that shared
// its cores took longer on the clock, not more CPU), else train seconds x threads; the restoration
// stages and the renders count their seconds x threads either way.
TEST(ArchiveTest, RunCpuSecondsPreferTheTrainingsCpuSeconds) {
  Results r;
  r.method_info = {{"train_seconds", 2000.0}, {"filter_seconds", 1.5}, {"detect_seconds", 0.5},
                   {"render_seconds", 0.25}, {"threads", 1}};
  EXPECT_DOUBLE_EQ(run_cpu_seconds(r), 2000 + 1.5 + 0.5 + 0.25);
  r.method_info["train_cpu_seconds"] = 640.0;
  EXPECT_DOUBLE_EQ(run_cpu_seconds(r), 640 + 1.5 + 0.5 + 0.25);
  r.method_info["threads"] = 2;  // CPU seconds already count every thread
  EXPECT_DOUBLE_EQ(run_cpu_seconds(r), 640 + 2 * (1.5 + 0.5 + 0.25));
  r.method_info.erase("train_cpu_seconds");
  EXPECT_DOUBLE_EQ(run_cpu_seconds(r), 2 * (2000 + 1.5 + 0.5 + 0.25));
}

TEST(RecipeDifferenceTest, NamesTheFirstDifferingKeyPath) {
  const Json a = recipe("weathergs"), b = recipe("weathergs", 7000);
  EXPECT_EQ(first_recipe_difference(a, b)->to_string(), "options/densify_until: 15000 vs 7000");
  Json c = a;
  c["weights"]["led"] = "abc";
  EXPECT_EQ(first_recipe_difference(a, c)->to_string(), "weights/led: none vs \"abc\"");
  EXPECT_FALSE(first_recipe_difference(a, a));
  EXPECT_EQ(recipe_fingerprint(a), recipe_fingerprint(Json::parse(a.dump())));
  EXPECT_NE(recipe_fingerprint(a), recipe_fingerprint(b));
  EXPECT_FALSE(first_recipe_difference(recipe_across_datasets(a), recipe_across_datasets(recipe("weathergs", 15000, "d2"))));
}

}  // namespace
}  // namespace weathergs::evaluator
