// Results on different data are never one row: results.json's dataset_identity, read and written,
// and how the leaderboard, the paper's tables and the regression check refuse or mark a mix.
#include <gtest/gtest.h>

#include <functional>

#include "core/atomic_file.h"
#include "evaluator/check.h"
#include "evaluator/leaderboard.h"
#include "evaluator/paper_tables.h"
#include "evaluator/results.h"
#include "tests/core/test_util.h"

namespace weathergs::evaluator {
namespace {

const std::string kDataA(64, 'a'), kDataB(64, 'b');

Results make(const std::string& method, const std::string& scene, double psnr, const std::string& identity) {
  Results r;
  r.method = method;
  r.scene = scene;
  r.weather = "rain";
  r.dataset = scene + "_rain";
  r.metrics = {psnr, 0.8, 0.2};
  r.per_view = {{"000", r.metrics}};
  if (!identity.empty()) r.dataset_identity = ScoredDataset{identity, 40, std::nullopt, std::nullopt};
  return r;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ResultsDatasetIdentity, RoundTripsAndOlderResultsReadAsUnknown) {
  testing::TempDir dir;
  Results r = make("m", "pool", 20, kDataA);
  r.dataset_identity->recorded_sha256 = kDataB;
  r.dataset_identity->first_difference = "images/003.png differs";
  write_results(dir / "r.json", r);
  const Json j = read_json_file(dir / "r.json");
  EXPECT_EQ(j.at("dataset_identity").at("scheme"), DatasetIdentity::kScheme);
  EXPECT_EQ(j.at("dataset_identity").at("sha256"), kDataA);
  EXPECT_EQ(j.at("dataset_identity").at("file_count"), 40);
  EXPECT_EQ(j.at("dataset_identity").at("differs_from_recorded").at("first_difference"), "images/003.png differs");
  const Results back = read_results(dir / "r.json");
  ASSERT_TRUE(back.dataset_identity);
  EXPECT_EQ(back.dataset_identity->sha256, kDataA);
  EXPECT_EQ(back.dataset_identity->file_count, 40u);
  EXPECT_EQ(back.dataset_identity->recorded_sha256, kDataB);
  EXPECT_EQ(short_dataset_identity(back), "aaaaaaaaaaaa");
  // A results file from before identities: read, and unknown.
  Json old = j;
  old.erase("dataset_identity");
  write_file_atomic(dir / "old.json", old.dump());
  const Results unknown = read_results(dir / "old.json");
  EXPECT_FALSE(unknown.dataset_identity);
  EXPECT_EQ(short_dataset_identity(unknown), "unknown");
  EXPECT_FALSE(results_to_json(unknown).contains("dataset_identity"));
  // Another scheme, a file list or an unknown key are errors naming the key.
  Json bad = j;
  bad["dataset_identity"]["scheme"] = "weathergs-dataset-identity-v9";
  write_file_atomic(dir / "bad.json", bad.dump());
  EXPECT_NE(error_of([&] { read_results(dir / "bad.json"); }).find("/dataset_identity/scheme"), std::string::npos);
  bad = j;
  bad["dataset_identity"]["files"] = Json::object();
  write_file_atomic(dir / "bad.json", bad.dump());
  EXPECT_NE(error_of([&] { read_results(dir / "bad.json"); }).find("/dataset_identity/files"), std::string::npos);
  bad = j;
  bad["dataset_identity"]["differs_from_recorded"]["why"] = "x";
  write_file_atomic(dir / "bad.json", bad.dump());
  EXPECT_NE(error_of([&] { read_results(dir / "bad.json"); }).find("'why'"), std::string::npos);
}

TEST(ResultsDatasetIdentity, WhatCountsAsDifferentData) {
  EXPECT_FALSE(dataset_identity_differs(make("m", "p", 1, kDataA), make("n", "p", 1, kDataA)));
  EXPECT_TRUE(dataset_identity_differs(make("m", "p", 1, kDataA), make("n", "p", 1, kDataB)));
  EXPECT_TRUE(dataset_identity_differs(make("m", "p", 1, kDataA), make("n", "p", 1, "")));
  EXPECT_TRUE(dataset_identity_differs(make("m", "p", 1, ""), make("n", "p", 1, kDataA)));
  EXPECT_FALSE(dataset_identity_differs(make("m", "p", 1, ""), make("n", "p", 1, "")));
}

TEST(LeaderboardMixedData, RefusedNamingBothFilesAndHashes) {
  const std::vector<LoadedResults> rs = {{"3dgs.json", make("3dgs", "pool", 20, kDataA)},
                                         {"wgs.json", make("weathergs", "pool", 25, kDataA)},
                                         {"nerf.json", make("nerf", "pool", 18, kDataB)}};
  const std::string e = error_of([&] { build_leaderboard(rs); });
  EXPECT_NE(e.find("nerf.json"), std::string::npos) << e;
  EXPECT_NE(e.find("3dgs.json"), std::string::npos) << e;
  EXPECT_NE(e.find(kDataA), std::string::npos) << e;
  EXPECT_NE(e.find(kDataB), std::string::npos) << e;
  EXPECT_NE(e.find("--allow-mixed-data"), std::string::npos) << e;
  // The paper's tables are built on the same columns.
  EXPECT_THROW(build_paper_tables(rs), InputError);
  // A result without an identity among results with one is not known to be on their data.
  const std::vector<LoadedResults> old = {{"new.json", make("3dgs", "pool", 20, kDataA)},
                                          {"old.json", make("nerf", "pool", 18, "")}};
  const std::string e2 = error_of([&] { build_leaderboard(old); });
  EXPECT_NE(e2.find("old.json"), std::string::npos) << e2;
  EXPECT_NE(e2.find("none recorded"), std::string::npos) << e2;
  // Without any identity (results from before they were recorded), or one dataset per column: as always.
  EXPECT_NO_THROW(build_leaderboard({{"a", make("3dgs", "pool", 20, "")}, {"b", make("nerf", "pool", 18, "")}}));
  EXPECT_NO_THROW(build_leaderboard({{"a", make("3dgs", "pool", 20, kDataA)}, {"b", make("3dgs", "yard", 18, kDataB)}}));
}

TEST(LeaderboardMixedData, AllowedTheOddCellsAreMarkedAndNeverBold) {
  // pool: two results on A (the column's data), one on B, whose PSNR is the column's best.
  const std::vector<LoadedResults> rs = {{"a", make("3dgs", "pool", 20, kDataA)},
                                         {"b", make("weathergs", "pool", 25, kDataA)},
                                         {"c", make("nerf", "pool", 30, kDataB)},
                                         {"d", make("3dgs", "yard", 21, kDataA)}};
  LeaderboardOptions allow;
  allow.allow_mixed_data = true;
  const auto tables = build_leaderboard(rs, allow);
  ASSERT_EQ(tables.size(), 1u);
  const LeaderboardTable& t = tables[0];
  ASSERT_EQ(t.methods, (std::vector<std::string>{"3dgs", "weathergs", "nerf"}));
  EXPECT_FALSE(t.cells[0][0].other_data);
  EXPECT_FALSE(t.cells[1][0].other_data);
  EXPECT_TRUE(t.cells[2][0].other_data);
  ASSERT_EQ(t.data_notes.size(), 1u);
  EXPECT_EQ(t.data_notes[0], "pool: 2 on aaaaaaaaaaaa (the column's); 1 on bbbbbbbbbbbb (nerf)");
  const std::string md = render_leaderboard(tables, TableFormat::kMarkdown);
  EXPECT_NE(md.find("| nerf | 30.00 † |"), std::string::npos) << md;
  EXPECT_NE(md.find("**25.00**"), std::string::npos) << md;  // the best on the column's own data
  EXPECT_EQ(md.find("**30.00**"), std::string::npos) << md;
  EXPECT_NE(md.find("pool: 2 on aaaaaaaaaaaa (the column's); 1 on bbbbbbbbbbbb (nerf)"), std::string::npos) << md;
  const std::string csv = render_leaderboard(tables, TableFormat::kCsv);
  EXPECT_NE(csv.find(",other_data\n"), std::string::npos) << csv;
  EXPECT_NE(csv.find(",pool\n"), std::string::npos) << csv;
  const std::string tex = render_leaderboard(tables, TableFormat::kLatex);
  EXPECT_NE(tex.find("30.00$^\\dagger$"), std::string::npos) << tex;
  EXPECT_NE(tex.find("{\\footnotesize $^\\dagger$"), std::string::npos) << tex;
  const std::string html = render_leaderboard(tables, TableFormat::kHtml);
  EXPECT_NE(html.find("30.00 &dagger;"), std::string::npos) << html;
  // Unmixed tables keep their layout: no marker column in the CSV.
  const auto plain = build_leaderboard({rs[0], rs[1], rs[3]}, allow);
  EXPECT_EQ(render_leaderboard(plain, TableFormat::kCsv).find("other_data"), std::string::npos);
  EXPECT_EQ(render_leaderboard(plain, TableFormat::kMarkdown).find("†"), std::string::npos);
}

TEST(LeaderboardMixedData, PaperTablesMarkTheAblationAndThePairs) {
  std::vector<LoadedResults> rs = {{"1", make("3dgs", "pool", 20, kDataA)},
                                   {"2", make("weathergs", "pool", 25, kDataB)},
                                   {"3", make("weathergs", "pool", 24, kDataB)},
                                   {"4", make("weathergs-no-led", "pool", 23, kDataB)},
                                   {"5", make("3dgs", "pool", 21, kDataA)}};
  for (auto& lr : rs) lr.results.method_info = {{"seed", std::stoi(lr.path) % 2}};
  LeaderboardOptions allow;
  allow.allow_mixed_data = true;
  const PaperTables t = build_paper_tables(rs, allow);
  // B holds three results, A two: the column's data is B and 3dgs is the odd one.
  EXPECT_EQ(t.data_notes, (std::vector<std::string>{"pool rain: 2 on aaaaaaaaaaaa (3dgs); 3 on bbbbbbbbbbbb (the column's)"}));
  ASSERT_EQ(t.ablation.methods, (std::vector<std::string>{"weathergs-no-led", "weathergs"}));
  EXPECT_FALSE(t.ablation.average[0].other_data);
  EXPECT_FALSE(t.ablation.average[1].other_data);
  ASSERT_FALSE(t.differences.empty());
  EXPECT_EQ(t.differences[0].method, "weathergs");
  EXPECT_EQ(t.differences[0].baseline, "3dgs");
  EXPECT_TRUE(t.differences[0].other_data);
  const std::string md = render_paper_tables(t, TableFormat::kMarkdown);
  EXPECT_NE(md.find("| weathergs − 3dgs †"), std::string::npos) << md;
  EXPECT_NE(md.find("3 on bbbbbbbbbbbb (the column's)"), std::string::npos) << md;
}

TEST(CheckDataIdentity, OtherDataIsRefusedUnlessAllowed) {
  const std::vector<LoadedResults> base = {{"base.json", make("wgs", "pool", 25, kDataA)}};
  CheckOptions o;
  EXPECT_TRUE(check_regression(base, {{"new.json", make("wgs", "pool", 25, kDataA)}}, o).passed);
  const std::vector<LoadedResults> other = {{"new.json", make("wgs", "pool", 25, kDataB)}};
  const std::string e = error_of([&] { check_regression(base, other, o); });
  EXPECT_NE(e.find("new.json"), std::string::npos) << e;
  EXPECT_NE(e.find("base.json"), std::string::npos) << e;
  EXPECT_NE(e.find(kDataA), std::string::npos) << e;
  EXPECT_NE(e.find(kDataB), std::string::npos) << e;
  EXPECT_NE(e.find("--allow-other-data"), std::string::npos) << e;
  // A new result that records none, against a baseline that does: refused too.
  EXPECT_THROW(check_regression(base, {{"new.json", make("wgs", "pool", 25, "")}}, o), InputError);
  // A baseline from before identities compares as before, and says so.
  const CheckReport old = check_regression({{"base.json", make("wgs", "pool", 25, "")}}, other, o);
  EXPECT_TRUE(old.passed);
  EXPECT_NE(old.text.find("the baseline records no dataset identity"), std::string::npos) << old.text;
  o.allow_other_data = true;
  const CheckReport r = check_regression(base, other, o);
  EXPECT_TRUE(r.passed);
  EXPECT_NE(r.text.find("other data than the baseline (allowed)"), std::string::npos) << r.text;
  EXPECT_EQ(r.json.at("datasets").at(0).at("other_data"), true);
}

TEST(CheckDataIdentity, AnotherScheduleIsAnotherRecipe) {
  Results b = make("wgs", "pool", 25, kDataA);
  b.method_info = {{"schedule", "fast"}, {"iterations", 3000}};
  Results n = b;
  n.method_info["schedule"] = "reference";
  CheckOptions o;
  const std::string e = error_of([&] { check_regression({{"base.json", b}}, {{"new.json", n}}, o); });
  EXPECT_NE(e.find("method_info.schedule is \"reference\", the baseline's \"fast\""), std::string::npos) << e;
  EXPECT_NE(e.find("--allow-other-recipe"), std::string::npos) << e;
  o.allow_other_recipe = true;
  const CheckReport r = check_regression({{"base.json", b}}, {{"new.json", n}}, o);
  EXPECT_TRUE(r.passed);
  EXPECT_NE(r.text.find("another recipe than the baseline (allowed): method_info.schedule"), std::string::npos) << r.text;
}

}  // namespace
}  // namespace weathergs::evaluator
