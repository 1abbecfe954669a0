// Results of other recipes are never tabulated as one (evaluator/leaderboard.h, find_mixed_recipes):
// a method's runs must share everything but what their dataset makes of the recipe, a backend's its
// numerics, every run the LPIPS weights; refused naming both files and the first differing key, or,
// when allowed, marked with a double dagger, never bold, with a note (also in the paper's tables).
#include <gtest/gtest.h>

#include <functional>

#include "evaluator/leaderboard.h"
#include "evaluator/paper_tables.h"
#include "evaluator/recipe.h"

namespace weathergs::evaluator {
namespace {

Json recipe(const std::string& method, const std::string& backend = "3dgs") {
  return {{"method", method},
          {"backend", backend},
          {"numerics", backend + "-numerics-1"},
          {"options", {{"densify_until", 15000}}},
          {"run_length", {{"iterations", 7000}}},
          {"points", "dataset"},
          {"dataset", "d-pool"},
          {"weights", Json::object()},
          {"scoring", {{"lpips", "alex_v0.1"}, {"lpips_sha256", "8fb3b215c4fa"}}}};
}

Results make(const std::string& method, const std::string& scene, double psnr, int seed, Json r) {
  Results res;
  res.method = method;
  res.scene = scene;
  res.weather = "rain";
  res.dataset = scene + "_rain";
  res.metrics = {psnr, 0.8, 0.2};
  res.per_view = {{"000", res.metrics}};
  res.method_info = {{"seed", seed}};
  if (!r.is_null()) {
    r["dataset"] = "d-" + scene;
    res.method_info[kRecipeKey] = r;
    res.method_info[kRecipeFingerprintKey] = recipe_fingerprint(r);
  }
  return res;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

Json with(Json r, const std::string& pointer, const Json& value) {
  r[Json::json_pointer(pointer)] = value;
  return r;
}

TEST(LeaderboardMixedRecipes, AMethodsRunsShareTheirRecipeAcrossSeedsAndVariants) {
  const Json w = recipe("weathergs");
  // Seeds and variants of one recipe, and other methods with other options: one leaderboard.
  const std::vector<LoadedResults> ok = {{"w0.json", make("weathergs", "pool", 25, 0, w)},
                                         {"w1.json", make("weathergs", "pool", 26, 1, w)},
                                         {"wy.json", make("weathergs", "yard", 24, 0, with(w, "/run_length/iterations", 9000))},
                                         {"g.json", make("3dgs", "pool", 20, 0, with(recipe("3dgs"), "/options/densify_until", 1))}};
  EXPECT_NO_THROW(build_leaderboard(ok));
  // Another option on one seed: refused, naming both files and the key.
  std::vector<LoadedResults> rs = ok;
  rs.push_back({"w2.json", make("weathergs", "pool", 27, 2, with(w, "/options/densify_until", 7000))});
  const std::string e = error_of([&] { build_leaderboard(rs); });
  EXPECT_NE(e.find("w2.json"), std::string::npos) << e;
  EXPECT_NE(e.find("w0.json"), std::string::npos) << e;
  EXPECT_NE(e.find("options/densify_until: 7000 vs 15000"), std::string::npos) << e;
  EXPECT_NE(e.find("--allow-mixed-recipes"), std::string::npos) << e;
  EXPECT_THROW(build_paper_tables(rs), InputError);
  // Another run length within one variant (the same dataset made another length): refused.
  const std::string e2 = error_of([&] {
    build_leaderboard({ok[0], {"w3.json", make("weathergs", "pool", 25, 3, with(w, "/run_length/iterations", 6000))}});
  });
  EXPECT_NE(e2.find("run_length/iterations: 6000 vs 7000"), std::string::npos) << e2;
  // Other weights across variants: refused.
  EXPECT_NE(error_of([&] {
              build_leaderboard({ok[0], {"wl.json", make("weathergs", "yard", 25, 0, with(w, "/weights/led", "abc"))}});
            }).find("weights/led"),
            std::string::npos);
}

TEST(LeaderboardMixedRecipes, OneNumericsPerBackendOneLpipsAndUnknownRecipes) {
  const std::vector<LoadedResults> numerics = {
      {"a.json", make("3dgs", "pool", 20, 0, recipe("3dgs"))},
      {"b.json", make("weathergs", "pool", 25, 0, with(recipe("weathergs"), "/numerics", "3dgs-numerics-2"))},
      {"n.json", make("nerf", "pool", 18, 0, recipe("nerf", "nerf"))}};
  const std::string e = error_of([&] { build_leaderboard(numerics); });
  EXPECT_NE(e.find("b.json"), std::string::npos) << e;
  EXPECT_NE(e.find("backend 3dgs: its runs share the trainer-numerics version"), std::string::npos) << e;
  const std::string lpips = error_of([&] {
    build_leaderboard({numerics[0], {"l.json", make("nerf", "pool", 18, 0, with(recipe("nerf", "nerf"), "/scoring/lpips_sha256", "x"))}});
  });
  EXPECT_NE(lpips.find("LPIPS"), std::string::npos) << lpips;
  // A result that records no recipe among its method's that do: unknown, refused; none recorded by
  // any (results from before recipes): compared as before.
  const std::string old = error_of([&] { build_leaderboard({numerics[0], {"old.json", make("3dgs", "yard", 21, 0, Json())}}); });
  EXPECT_NE(old.find("old.json"), std::string::npos) << old;
  EXPECT_NE(old.find("records no recipe"), std::string::npos) << old;
  EXPECT_NO_THROW(build_leaderboard({{"x", make("3dgs", "pool", 20, 0, Json())}, {"y", make("3dgs", "yard", 21, 0, Json())}}));
  // An edited record (its fingerprint no longer its recipe's): refused.
  Results edited = make("3dgs", "pool", 20, 0, recipe("3dgs"));
  edited.method_info[kRecipeKey]["options"]["densify_until"] = 2;
  EXPECT_NE(error_of([&] { build_leaderboard({{"edited.json", edited}}); }).find("edited.json"), std::string::npos);
}

TEST(LeaderboardMixedRecipes, AllowedTheOddCellsAreMarkedNeverBoldAndNoted) {
  const Json w = recipe("weathergs");
  const std::vector<LoadedResults> rs = {{"w0", make("weathergs", "pool", 25, 0, w)},
                                         {"w1", make("weathergs", "pool", 25, 1, w)},
                                         {"w2", make("weathergs", "yard", 30, 0, with(w, "/options/densify_until", 7000))},
                                         {"g0", make("3dgs", "pool", 20, 0, recipe("3dgs"))},
                                         {"g1", make("3dgs", "yard", 21, 0, recipe("3dgs"))}};
  LeaderboardOptions allow;
  allow.allow_mixed_recipes = true;
  const auto tables = build_leaderboard(rs, allow);
  ASSERT_EQ(tables.size(), 1u);
  const LeaderboardTable& t = tables[0];
  ASSERT_EQ(t.methods, (std::vector<std::string>{"weathergs", "3dgs"}));
  EXPECT_FALSE(t.cells[0][0].other_recipe);
  EXPECT_TRUE(t.cells[0][1].other_recipe);
  EXPECT_TRUE(t.average[0].other_recipe);
  EXPECT_FALSE(t.cells[1][1].other_recipe);
  ASSERT_EQ(t.recipe_notes.size(), 1u);
  EXPECT_EQ(t.recipe_notes[0].rfind("weathergs: 2 on recipe ", 0), 0u) << t.recipe_notes[0];
  EXPECT_NE(t.recipe_notes[0].find("(the group's); 1 on recipe "), std::string::npos) << t.recipe_notes[0];
  EXPECT_NE(t.recipe_notes[0].find("(options/densify_until)"), std::string::npos) << t.recipe_notes[0];
  const std::string md = render_leaderboard(tables, TableFormat::kMarkdown);
  EXPECT_NE(md.find("30.00 ‡"), std::string::npos) << md;
  EXPECT_EQ(md.find("**30.00**"), std::string::npos) << md;  // never bold
  EXPECT_NE(md.find("**21.00**"), std::string::npos) << md;  // the best of one recipe is
  EXPECT_NE(md.find("‡ Includes runs made with another recipe"), std::string::npos) << md;
  EXPECT_NE(render_leaderboard(tables, TableFormat::kCsv).find(",other_recipe\n"), std::string::npos);
  EXPECT_NE(render_leaderboard(tables, TableFormat::kLatex).find("30.00$^\\ddagger$"), std::string::npos);
  EXPECT_NE(render_leaderboard(tables, TableFormat::kHtml).find("30.00 &Dagger;"), std::string::npos);
  // The paper's tables: the quality cells, the ablation's average and the pairs.
  const PaperTables p = build_paper_tables(rs, allow);
  ASSERT_FALSE(p.ablation.methods.empty());
  EXPECT_TRUE(p.ablation.average.back().other_recipe);
  ASSERT_FALSE(p.differences.empty());
  EXPECT_TRUE(p.differences[0].other_recipe);
  EXPECT_NE(render_paper_tables(p, TableFormat::kMarkdown).find("| weathergs − 3dgs ‡"), std::string::npos);
}

}  // namespace
}  // namespace weathergs::evaluator
