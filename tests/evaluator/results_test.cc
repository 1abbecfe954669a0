#include <gtest/gtest.h>

#include <functional>

#include <cmath>
#include <limits>

#include "core/atomic_file.h"
#include "evaluator/check.h"
#include "evaluator/leaderboard.h"
#include "evaluator/paper_tables.h"
#include "evaluator/results.h"
#include "tests/core/test_util.h"

namespace weathergs::evaluator {
namespace {

Results make(const std::string& method, const std::string& scene, const std::string& weather, double psnr,
             double ssim, std::optional<double> lpips) {
  Results r;
  r.method = method;
  r.scene = scene;
  r.weather = weather;
  r.dataset = scene + "_" + weather;
  r.metrics = {psnr, ssim, lpips};
  r.per_view = {{"000", r.metrics}};
  return r;
}

TEST(ResultsTest, JsonRoundTripWithInfinitePsnrAndSkippedLpips) {
  testing::TempDir dir;
  Results r = make("m", "pool", "rain", std::numeric_limits<double>::infinity(), 1.0, std::nullopt);
  r.protocol.lpips.reset();
  r.method_info = {{"iterations", 7000}};
  write_results(dir / "r.json", r);
  Json j = read_json_file(dir / "r.json");
  EXPECT_TRUE(j["metrics"]["psnr"].is_null());
  EXPECT_EQ(j["metrics"]["psnr_infinite"], true);
  EXPECT_TRUE(j["metrics"]["lpips"].is_null());
  EXPECT_TRUE(j["protocol"]["lpips"].is_null());
  Results back = read_results(dir / "r.json");
  EXPECT_TRUE(std::isinf(back.metrics.psnr));
  EXPECT_FALSE(back.metrics.lpips);
  EXPECT_EQ(back.method_info["iterations"], 7000);
  EXPECT_EQ(back.protocol, r.protocol);
}

TEST(ResultsTest, StrictReading) {
  testing::TempDir dir;
  Json j = results_to_json(make("m", "pool", "rain", 20, 0.5, 0.2));
  j["metrics"]["psnrr"] = 3;
  write_file_atomic(dir / "bad.json", j.dump());
  try {
    read_results(dir / "bad.json");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.json:/metrics"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'psnrr'"), std::string::npos) << e.what();
  }
  j = results_to_json(make("m", "pool", "rain", 20, 0.5, 0.2));
  j["metrics"]["ssim"] = "high";
  write_file_atomic(dir / "bad2.json", j.dump());
  EXPECT_THROW(read_results(dir / "bad2.json"), InputError);
  write_file_atomic(dir / "bad3.json", "{\"format\": \"weathergs-results\", ");
  EXPECT_THROW(read_results(dir / "bad3.json"), InputError);
}

std::vector<LoadedResults> paper_like() {
  return {{"a", make("3dgs", "tanabata", "snow", 20.0, 0.70, 0.30)},
          {"b", make("3dgs", "pool", "snow", 22.0, 0.80, 0.20)},
          {"c", make("weathergs", "tanabata", "snow", 25.0, 0.85, 0.15)},
          {"d", make("weathergs", "pool", "snow", 21.0, 0.82, 0.18)},
          {"e", make("nerf", "tanabata", "snow", 18.0, 0.60, 0.40)},
          {"f", make("weathergs", "pool", "rain", 27.0, 0.90, 0.10)}};
}

TEST(LeaderboardTest, TablesPerWeatherBestAndAverage) {
  auto tables = build_leaderboard(paper_like());
  ASSERT_EQ(tables.size(), 2u);
  const LeaderboardTable& snow = tables[0];
  EXPECT_EQ(snow.weather, "snow");
  EXPECT_EQ(snow.scenes, (std::vector<std::string>{"tanabata", "pool"}));
  EXPECT_EQ(snow.methods, (std::vector<std::string>{"3dgs", "weathergs", "nerf"}));
  EXPECT_DOUBLE_EQ(snow.average[1].psnr, 23.0);
  EXPECT_EQ(snow.average[2].n, 0);  // nerf lacks pool: no average
  std::string md = render_leaderboard(tables, TableFormat::kMarkdown);
  EXPECT_NE(md.find("## Weather: Snow"), std::string::npos);
  EXPECT_NE(md.find("**25.00**"), std::string::npos) << md;   // best tanabata PSNR
  EXPECT_NE(md.find("**22.00**"), std::string::npos) << md;   // best pool PSNR is 3dgs
  EXPECT_NE(md.find("**0.150**"), std::string::npos) << md;   // lowest LPIPS is bold
  EXPECT_EQ(md.find("**0.400**"), std::string::npos) << md;
  EXPECT_NE(md.find("| nerf | 18.00 | 0.600 | 0.400 | – |"), std::string::npos) << md;
  std::string csv = render_leaderboard(tables, TableFormat::kCsv);
  EXPECT_NE(csv.find("weather,method,tanabata_psnr,tanabata_ssim,tanabata_lpips"), std::string::npos) << csv;
  std::string tex = render_leaderboard(tables, TableFormat::kLatex);
  EXPECT_NE(tex.find("\\multicolumn{3}{c}{tanabata}"), std::string::npos);
  EXPECT_NE(tex.find("\\textbf{25.00}"), std::string::npos);
  std::string html = render_leaderboard(tables, TableFormat::kHtml);
  EXPECT_NE(html.find("<b>25.00</b>"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);  // self-contained
  EXPECT_EQ(html.find("<script src"), std::string::npos);
}

// A note says what the tables are (a smoke run, not converged): the first paragraph under the title
// in Markdown and HTML (escaped), comment lines in LaTeX (so that the tables \input into a paper print
// nothing more); CSV holds data only and refuses one; without a note nothing changes.
TEST(LeaderboardTest, ANoteSaysWhatTheTablesAre) {
  const auto tables = build_leaderboard(paper_like());
  const std::string note = "A smoke run at 1000 iterations, not converged: see <docs/results.md> & the archive.";
  const std::string md = render_leaderboard(tables, TableFormat::kMarkdown, note);
  EXPECT_EQ(md.rfind("# Leaderboard\n\n" + note + "\n\n## Weather: Snow", 0), 0u) << md;
  const std::string html = render_leaderboard(tables, TableFormat::kHtml, note);
  const std::string escaped = "<p class=\"run-note\">A smoke run at 1000 iterations, not converged: see "
                              "&lt;docs/results.md&gt; &amp; the archive.</p>\n";
  EXPECT_NE(html.find("<h1>Leaderboard</h1>\n" + escaped), std::string::npos) << html;
  const std::string tex = render_leaderboard(tables, TableFormat::kLatex, "line one\nline two");
  EXPECT_NE(tex.find("booktabs,graphicx}\n% line one\n% line two\n"), std::string::npos) << tex;
  EXPECT_THROW(render_leaderboard(tables, TableFormat::kCsv, note), InputError);
  for (TableFormat f : {TableFormat::kMarkdown, TableFormat::kCsv, TableFormat::kLatex, TableFormat::kHtml})
    EXPECT_EQ(render_leaderboard(tables, f, ""), render_leaderboard(tables, f)) << int(f);
  // The paper's tables take the same note.
  const std::string paper = render_paper_tables(build_paper_tables(paper_like()), TableFormat::kMarkdown, note);
  EXPECT_EQ(paper.rfind("# WeatherGS benchmark: the paper's tables\n\n" + note + "\n\n## Table I", 0), 0u) << paper;
  EXPECT_THROW(render_paper_tables(build_paper_tables(paper_like()), TableFormat::kCsv, note), InputError);
}

// The oracle is an upper bound, not a competitor: every format shows it as a reference line and
// never bolds it, as the paper's tables do.
TEST(LeaderboardTest, TheOracleIsAReferenceLineInEveryFormat) {
  std::vector<LoadedResults> rs = {{"a", make("3dgs", "pool", "rain", 24.0, 0.80, 0.30)},
                                   {"b", make("oracle", "pool", "rain", 31.0, 0.90, 0.10)}};
  const auto tables = build_leaderboard(rs);
  ASSERT_EQ(tables.size(), 1u);
  const std::string md = render_leaderboard(tables, TableFormat::kMarkdown);
  const std::string html = render_leaderboard(tables, TableFormat::kHtml);
  EXPECT_NE(md.find("oracle (reference)"), std::string::npos) << md;
  EXPECT_EQ(md.find("**31.00**"), std::string::npos) << md;
  EXPECT_NE(md.find("**24.00**"), std::string::npos) << md;
  EXPECT_EQ(html.find("<b>31.00</b>"), std::string::npos) << html;
  EXPECT_NE(html.find("<b>24.00</b>"), std::string::npos) << html;
}

TEST(LeaderboardTest, RepeatedRunsShowSpreadAndProtocolsMustMatch) {
  std::vector<LoadedResults> rs = {{"s1", make("3dgs", "pool", "rain", 20.0, 0.7, 0.3)},
                                   {"s2", make("3dgs", "pool", "rain", 22.0, 0.7, 0.3)}};
  auto tables = build_leaderboard(rs);
  EXPECT_EQ(tables[0].cells[0][0].n, 2);
  EXPECT_DOUBLE_EQ(tables[0].cells[0][0].psnr, 21.0);
  EXPECT_DOUBLE_EQ(tables[0].cells[0][0].psnr_std, 1.0);
  EXPECT_NE(render_leaderboard(tables, TableFormat::kMarkdown).find("21.00 ± 1.00"), std::string::npos);
  rs[1].results.protocol.ssim = "gaussian11_sigma1.5_same";
  EXPECT_THROW(build_leaderboard(rs), InputError);
  EXPECT_THROW(parse_table_format("pdf"), InputError);
}

TEST(PaperTablesTest, SnowRainAblationAndCostWithReferenceLines) {
  std::vector<LoadedResults> rs;
  auto add = [&](const std::string& m, const std::string& scene, const std::string& w, double psnr, double train_s) {
    Results r = make(m, scene, w, psnr, 0.8, 0.2);
    r.per_view = {{"000", r.metrics}, {"001", r.metrics}};
    r.method_info = {{"train_seconds", train_s}, {"render_seconds", 0.5}, {"peak_rss_mb", 300.0}, {"num_gaussians", 1000}};
    if (m.rfind("weathergs", 0) == 0) r.method_info["filter_seconds"] = 2.0;
    if (m == "weathergs") r.method_info["detect_seconds"] = 1.0;
    rs.push_back({m + scene + w + std::to_string(rs.size()), r});
  };
  // Rain comes first in the files; Table I is still snow.
  add("oracle", "pool", "rain", 40, 100);
  add("3dgs", "pool", "rain", 20, 100);
  add("3dgs", "pool", "rain", 22, 120);  // a second seed
  add("weathergs", "pool", "rain", 24, 100);
  add("weathergs", "pool", "snow", 26, 100);
  add("3dgs", "pool", "snow", 21, 100);
  add("weathergs-no-led", "pool", "rain", 23, 100);
  add("weathergs-no-led", "pool", "snow", 25, 100);
  add("weathergs-no-aef", "pool", "rain", 22, 100);  // lacks snow: no ablation average
  const PaperTables t = build_paper_tables(rs);
  ASSERT_EQ(t.quality.size(), 2u);
  EXPECT_EQ(t.quality[0].title, "Table I: Snow");
  EXPECT_EQ(t.quality[1].title, "Table II: Rain");
  const LeaderboardTable& rain = t.quality[1];
  EXPECT_EQ(rain.methods.back(), "oracle");  // reference lines last
  EXPECT_TRUE(rain.reference.back());
  EXPECT_DOUBLE_EQ(rain.cells[0][0].psnr, 21.0);  // 3dgs: two seeds averaged
  EXPECT_EQ(t.ablation_variants, (std::vector<std::string>{"pool_rain", "pool_snow"}));
  ASSERT_EQ(t.ablation.methods, (std::vector<std::string>{"weathergs-no-aef", "weathergs-no-led", "weathergs"}));
  EXPECT_EQ(t.ablation.average[0].n, 0);
  EXPECT_DOUBLE_EQ(t.ablation.average[1].psnr, 24.0);
  EXPECT_DOUBLE_EQ(t.ablation.average[2].psnr, 25.0);
  ASSERT_EQ(t.cost.back().method, "oracle");
  auto row = [&](const std::string& m) {
    for (const CostRow& c : t.cost)
      if (c.method == m) return c;
    ADD_FAILURE() << "no cost row " << m;
    return CostRow{};
  };
  const CostRow gs3 = row("3dgs");
  EXPECT_EQ(gs3.runs, 3);
  EXPECT_NEAR(gs3.train_seconds, 320.0 / 3, 1e-9);
  EXPECT_DOUBLE_EQ(gs3.render_ms_per_view, 250.0);
  EXPECT_DOUBLE_EQ(gs3.restoration_seconds, 0.0);
  EXPECT_DOUBLE_EQ(row("weathergs").restoration_seconds, 3.0);
  EXPECT_DOUBLE_EQ(row("weathergs-no-led").restoration_seconds, 2.0);
  const std::string md = render_paper_tables(t, TableFormat::kMarkdown);
  EXPECT_NE(md.find("## Table III: ablation, mean over all 2 variants"), std::string::npos) << md;
  EXPECT_NE(md.find("## Table IV: computational cost"), std::string::npos) << md;
  // The oracle's 40 dB is the best number but a reference line: shown, never bold.
  EXPECT_NE(md.find("| oracle (reference) | 40.00 |"), std::string::npos) << md;
  EXPECT_EQ(md.find("**40.00**"), std::string::npos) << md;
  EXPECT_NE(md.find("**24.00**"), std::string::npos) << md;
  for (TableFormat f : {TableFormat::kCsv, TableFormat::kLatex, TableFormat::kHtml}) {
    const std::string s = render_paper_tables(t, f);
    EXPECT_NE(s.find("weathergs-no-led"), std::string::npos);
    EXPECT_NE(s.find(f == TableFormat::kCsv ? "train_seconds" : "Table IV"), std::string::npos) << s;
  }
  // The ablation spans weathers, so its protocols must agree across them.
  rs[7].results.protocol.quantize_uint8 = false;
  EXPECT_THROW(build_paper_tables(rs), InputError);
}

TEST(CheckTest, PassesWithinToleranceFailsBeyond) {
  std::vector<LoadedResults> base = {{"base.json", make("wgs", "pool", "rain", 25.0, 0.85, 0.15)}};
  CheckOptions tol;
  // Within tolerance (0.1 dB drop, small SSIM drop, small LPIPS rise) and an improvement.
  std::vector<LoadedResults> ok = {{"new.json", make("wgs", "pool", "rain", 24.9, 0.847, 0.154)}};
  EXPECT_TRUE(check_regression(base, ok, tol).passed);
  std::vector<LoadedResults> better = {{"new.json", make("wgs", "pool", "rain", 26.0, 0.9, 0.1)}};
  EXPECT_TRUE(check_regression(base, better, tol).passed);
  // PSNR drop of 0.5 dB fails and the report says which metric.
  std::vector<LoadedResults> worse = {{"new.json", make("wgs", "pool", "rain", 24.5, 0.85, 0.15)}};
  CheckReport r = check_regression(base, worse, tol);
  EXPECT_FALSE(r.passed);
  EXPECT_NE(r.text.find("PSNR"), std::string::npos);
  EXPECT_NE(r.text.find("FAIL"), std::string::npos);
  EXPECT_EQ(r.json["passed"], false);
  // LPIPS rising beyond tolerance fails too.
  std::vector<LoadedResults> lp = {{"new.json", make("wgs", "pool", "rain", 25.0, 0.85, 0.16)}};
  EXPECT_FALSE(check_regression(base, lp, tol).passed);
  // A missing dataset fails; a protocol mismatch is not comparable (bad input).
  std::vector<LoadedResults> other = {{"new.json", make("wgs", "tanabata", "rain", 25, 0.85, 0.15)}};
  EXPECT_FALSE(check_regression(base, other, tol).passed);
  worse[0].results.protocol.quantize_uint8 = false;
  EXPECT_THROW(check_regression(base, worse, tol), InputError);
  tol.tolerances.psnr = -1;
  EXPECT_THROW(check_regression(base, ok, tol), InputError);
}

Results with_views(Results r, const std::vector<std::pair<std::string, MetricValues>>& views) {
  r.per_view = views;
  r.metrics = mean_metrics(views);
  return r;
}

TEST(CheckTest, EveryViewIsCheckedAsWellAsTheMean) {
  const Results b = with_views(make("wgs", "pool", "rain", 0, 0, 0), {{"000", {25.0, 0.85, 0.15}}, {"001", {27.0, 0.88, 0.12}}});
  std::vector<LoadedResults> base = {{"base.json", b}};
  CheckOptions o;  // mean tolerance 0.2 dB, per view 2 x 0.2 = 0.4 dB
  // The mean is within 0.2 dB, but view 001 fell by 0.6 dB (view 000 rose by 0.5).
  std::vector<LoadedResults> shifted = {
      {"new.json", with_views(b, {{"000", {25.5, 0.85, 0.15}}, {"001", {26.4, 0.88, 0.12}}})}};
  CheckReport r = check_regression(base, shifted, o);
  EXPECT_FALSE(r.passed) << r.text;
  EXPECT_NE(r.text.find("view 001 PSNR"), std::string::npos) << r.text;
  EXPECT_EQ(r.json["datasets"][0]["failed_views"].size(), 1u);
  // A view the baseline scored but the new result lacks fails.
  std::vector<LoadedResults> fewer = {{"new.json", with_views(b, {{"000", {25.0, 0.85, 0.15}}})}};
  EXPECT_FALSE(check_regression(base, fewer, o).passed);
  // Per-view tolerances from the tolerances file widen it.
  o.tolerances.view_psnr = 0.7;
  EXPECT_TRUE(check_regression(base, shifted, o).passed);
}

TEST(CheckTest, RefusesAnotherYardstickOtherWeightsOrAnotherRecipe) {
  Results b = make("wgs", "pool", "rain", 25.0, 0.85, 0.15);
  b.sha256_ground_truth = "aaaa";
  b.method_info = {{"weights", {{"led", "1111"}}}, {"method_description", "recipe A"}, {"iterations", 1000},
                   {"schedule", "fast"}, {"schedule_length", 7500}};
  std::vector<LoadedResults> base = {{"base.json", b}};
  auto variant = [&](const std::function<void(Results&)>& f) {
    Results n = b;
    f(n);
    return std::vector<LoadedResults>{{"new.json", n}};
  };
  CheckOptions o;
  EXPECT_TRUE(check_regression(base, variant([](Results&) {}), o).passed);
  // A changed ground truth is an error, never a pass.
  EXPECT_THROW(check_regression(base, variant([](Results& n) { n.sha256_ground_truth = "bbbb"; }), o), InputError);
  // Other weights, another recipe or another length: refused unless allowed.
  const auto other_weights = variant([](Results& n) { n.method_info["weights"]["led"] = "2222"; });
  const auto other_recipe = variant([](Results& n) { n.method_info["method_description"] = "recipe B"; });
  const auto longer = variant([](Results& n) { n.method_info["iterations"] = 2000; });
  const auto other_schedule = variant([](Results& n) { n.method_info["schedule"] = "reference"; });
  // The same 1000 iterations cut from another schedule length: another short form of the schedule.
  const auto other_form = variant([](Results& n) { n.method_info["schedule_length"] = 6000; });
  const auto unrecorded_form = variant([](Results& n) { n.method_info.erase("schedule_length"); });
  const auto unrecorded = variant([](Results& n) { n.method_info.erase("weights"); });
  for (const auto* c : {&other_weights, &unrecorded}) {
    try {
      check_regression(base, *c, o);
      ADD_FAILURE() << "accepted other weights";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--allow-other-weights"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(check_regression(base, other_recipe, o), InputError);
  EXPECT_THROW(check_regression(base, longer, o), InputError);
  for (const auto* c : {&other_schedule, &other_form, &unrecorded_form}) {
    try {
      check_regression(base, *c, o);
      ADD_FAILURE() << "accepted another schedule or form";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--allow-other-recipe"), std::string::npos) << e.what();
    }
  }
  o.allow_other_weights = true;
  o.allow_other_recipe = true;
  const CheckReport r = check_regression(base, other_weights, o);
  EXPECT_TRUE(r.passed);
  EXPECT_NE(r.text.find("other weights than the baseline (allowed)"), std::string::npos) << r.text;
  EXPECT_TRUE(check_regression(base, other_recipe, o).passed);
  EXPECT_TRUE(check_regression(base, other_form, o).passed);
}

TEST(CheckTest, InfinitePsnrComparesSanely) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<LoadedResults> base = {{"b", make("m", "s", "w", inf, 1.0, 0.0)}};
  std::vector<LoadedResults> same = {{"n", make("m", "s", "w", inf, 1.0, 0.0)}};
  EXPECT_TRUE(check_regression(base, same, CheckOptions{}).passed);
  std::vector<LoadedResults> finite = {{"n", make("m", "s", "w", 60.0, 1.0, 0.0)}};
  EXPECT_FALSE(check_regression(base, finite, CheckOptions{}).passed);
}

}  // namespace
}  // namespace weathergs::evaluator
