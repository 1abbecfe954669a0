// Carry-over between two results archives (evaluator/carry_over.h): the sign test against exact
// binomial sums, per-variant differences averaged over common seeds, the verdicts (holds, not
// significant, too few variants), refusals of an empty folder, a bad pair and mixed recipes.
// Hand-made archives, no training (~0.1 s).
#include <gtest/gtest.h>

#include <filesystem>

#include "evaluator/archive.h"
#include "evaluator/carry_over.h"
#include "evaluator/recipe.h"
#include "evaluator/statistics.h"
#include "tests/core/test_util.h"

namespace weathergs::evaluator {
namespace {

namespace fs = std::filesystem;
using weathergs::testing::TempDir;

// Exact: C(6,6)/64, (C(6,5)+C(6,6))/64, and the whole mass.
TEST(SignTest, MatchesExactBinomialSums) {
  EXPECT_DOUBLE_EQ(sign_test_p(6, 6), 1.0 / 64);
  EXPECT_NEAR(sign_test_p(5, 6), 7.0 / 64, 1e-12);
  EXPECT_NEAR(sign_test_p(3, 6), (20.0 + 15 + 6 + 1) / 64, 1e-12);
  EXPECT_DOUBLE_EQ(sign_test_p(0, 6), 1.0);
  EXPECT_NEAR(sign_test_p(5, 5), 1.0 / 32, 1e-12);
  EXPECT_NEAR(sign_test_p(40, 60), 0.00674464686559593, 1e-12);  // sum of C(60, i) / 2^60, i = 40..60, in exact integers
}

Json recipe(const std::string& method, const std::string& dataset, int densify_until = 15000) {
  return {{"method", method}, {"backend", "3dgs"}, {"numerics", "3dgs-numerics-1"},
          {"options", {{"densify_until", densify_until}}}, {"run_length", {{"iterations", 7000}}},
          {"points", "dataset"}, {"dataset", dataset}, {"weights", Json::object()}, {"scoring", {{"lpips", "alex_v0.1"}}}};
}

// One archived run: <suite>/<variant>/<method>/seed<N>/results.json with the given PSNR.
void put(const std::string& suite, const std::string& variant, const std::string& method, int seed, double psnr,
         int densify_until = 15000) {
  Results r;
  r.method = method;
  r.dataset = variant;
  r.scene = variant.substr(0, variant.find('_'));
  r.weather = variant.substr(variant.find('_') + 1);
  r.metrics = {psnr, 0.8, 0.2};
  r.per_view = {{"000", r.metrics}};
  const Json rec = recipe(method, variant, densify_until);
  r.method_info = {{"seed", seed}, {kRecipeKey, rec}, {kRecipeFingerprintKey, recipe_fingerprint(rec)}};
  const std::string dir = suite + "/" + variant + "/" + method + "/seed" + std::to_string(seed);
  fs::create_directories(dir);
  write_results(dir + "/results.json", r);
}

const CarryOverRow& row(const CarryOver& c, const std::string& a, const std::string& b, const std::string& metric) {
  for (const CarryOverRow& r : c.rows)
    if (r.pair.a == a && r.pair.b == b && r.metric == metric) return r;
  throw std::runtime_error("no row " + a + " - " + b + " " + metric);
}

TEST(CarryOverTest, PerVariantDifferencesSignTestAndVerdicts) {
  TempDir tmp;
  const std::string from = tmp / "quick", to = tmp / "paper";
  const char* variants[] = {"pool_rain", "pool_snow", "factory_rain", "factory_snow", "tanabata_rain", "tanabata_snow"};
  for (int i = 0; i < 6; ++i) {
    // Source: weathergs - 3dgs = +5 at seed 0 and +3 at seed 1 (mean +4); seed 2 of 3dgs alone is not paired.
    put(from, variants[i], "3dgs", 0, 20);
    put(from, variants[i], "weathergs", 0, 25);
    put(from, variants[i], "3dgs", 1, 20);
    put(from, variants[i], "weathergs", 1, 23);
    put(from, variants[i], "3dgs", 2, 10);
    // Target: +1 on five variants, -1 on the last.
    put(to, variants[i], "3dgs", 0, 20);
    put(to, variants[i], "weathergs", 0, i < 5 ? 21 : 19);
  }
  // The oracle's gap on two variants only: too few for the test.
  for (const char* v : {"pool_rain", "tanabata_snow"}) {
    put(from, v, "oracle", 0, 30);
    put(to, v, "oracle", 0, 28);
  }
  const CarryOver c = carry_over(from, to, parse_carry_over_pairs(kDefaultCarryOverPairs, "--pairs"));
  EXPECT_EQ(c.from_runs, 6 * 5 + 2);
  EXPECT_EQ(c.to_runs, 6 * 2 + 2);
  const CarryOverRow& g = row(c, "weathergs", "3dgs", "psnr");
  ASSERT_EQ(g.variants.size(), 6u);
  EXPECT_DOUBLE_EQ(g.from[0], 4.0);
  EXPECT_EQ(g.from_seeds[0], 2);  // seed 2 has no weathergs run
  EXPECT_EQ(g.to_seeds[0], 1);
  EXPECT_DOUBLE_EQ(g.from_mean, 4.0);
  EXPECT_NEAR(g.to_mean, 4.0 / 6, 1e-12);
  EXPECT_EQ(g.agree, 5);
  EXPECT_NEAR(g.p, 7.0 / 64, 1e-12);
  EXPECT_EQ(g.verdict, "same sign on 5 of 6, not significant");
  // SSIM is equal everywhere: no sign to carry.
  EXPECT_NE(row(c, "weathergs", "3dgs", "ssim").verdict.find("no sign to carry"), std::string::npos);
  const CarryOverRow& o = row(c, "oracle", "weathergs", "psnr");  // oracle - weathergs: source +5 / +5, target +7 / +9
  EXPECT_EQ(o.variants, (std::vector<std::string>{"pool_rain", "tanabata_snow"}));
  EXPECT_EQ(o.agree, 2);
  EXPECT_NE(o.verdict.find("too few variants for the test"), std::string::npos) << o.verdict;
  EXPECT_DOUBLE_EQ(row(c, "oracle", "3dgs", "psnr").to_mean, 8.0);  // the weather's whole cost: 28 - 20
  ASSERT_EQ(c.notes.size(), 1u);  // no weathergs-no-aef anywhere
  EXPECT_NE(c.notes[0].find("weathergs - weathergs-no-aef"), std::string::npos);
  const std::string md = render_carry_over(c);
  EXPECT_NE(md.find("| weathergs - 3dgs | PSNR | 6 | +4.00 dB | +0.67 dB | 0.17 | 5 of 6 | 0.109 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| pool_rain | +4.00 (2) | +1.00 (1) |"), std::string::npos) << md;
  // Six of six agreeing holds.
  put(to, "tanabata_snow", "weathergs", 0, 22);
  const CarryOver all = carry_over(from, to, {{"weathergs", "3dgs"}});
  EXPECT_EQ(row(all, "weathergs", "3dgs", "psnr").verdict, "holds: same sign on 6 of 6");
}

// A target suite that has begun: one run, so no pair yet. The page says so instead of an empty table.
TEST(CarryOverTest, ATargetWithNoPairYetSaysSo) {
  TempDir tmp;
  const std::string from = tmp / "quick", to = tmp / "paper";
  put(from, "pool_rain", "3dgs", 0, 20);
  put(from, "pool_rain", "weathergs", 0, 25);
  put(to, "pool_rain", "weathergs", 0, 24);
  const CarryOver c = carry_over(from, to, {{"weathergs", "3dgs"}});
  EXPECT_TRUE(c.rows.empty());
  const std::string md = render_carry_over(c);
  EXPECT_NE(md.find("(1 run). Per variant"), std::string::npos) << md;
  EXPECT_NE(md.find("No paired difference has both methods in both suites yet."), std::string::npos) << md;
  EXPECT_EQ(md.find("| A - B |"), std::string::npos) << md;
  EXPECT_NE(md.find("- weathergs - 3dgs: no variant where both suites ran both methods"), std::string::npos) << md;
}

TEST(CarryOverTest, RefusesEmptyFoldersBadPairsAndMixedRecipes) {
  TempDir tmp;
  const std::string from = tmp / "quick", to = tmp / "paper";
  put(from, "pool_rain", "3dgs", 0, 20);
  fs::create_directories(to);
  EXPECT_THROW(carry_over(from, to, {{"weathergs", "3dgs"}}), InputError);
  EXPECT_THROW(parse_carry_over_pairs("weathergs-3dgs", "--pairs"), InputError);
  EXPECT_THROW(parse_carry_over_pairs("a:a", "--pairs"), InputError);
  EXPECT_THROW(parse_carry_over_pairs("", "--pairs"), InputError);
  put(to, "pool_rain", "3dgs", 0, 20);
  put(to, "pool_snow", "3dgs", 0, 20, 9000);  // one method, two recipes in one suite
  try {
    carry_over(from, to, {{"weathergs", "3dgs"}});
    ADD_FAILURE() << "a suite of mixed recipes was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("densify_until"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace weathergs::evaluator
