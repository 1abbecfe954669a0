// The method table (methods/method.h): one row per method, whose columns every caller reads.
#include <gtest/gtest.h>

#include <set>

#include "evaluator/leaderboard.h"
#include "methods/backend.h"
#include "methods/method.h"

namespace weathergs::methods {
namespace {

TEST(MethodTest, EveryMethodHasOneRowAndItsNameParsesBack) {
  std::set<std::string> names;
  for (Method m : all_methods()) {
    EXPECT_EQ(spec(m).method, m);
    EXPECT_TRUE(names.insert(spec(m).name).second) << spec(m).name;
    EXPECT_EQ(parse_method(spec(m).name, "test"), m);
    EXPECT_FALSE(std::string(spec(m).description).empty()) << spec(m).name;
  }
  EXPECT_EQ(names.size(), 14u);
  EXPECT_THROW(parse_method("nerfz", "--method"), InputError);
}

// The evaluator cannot read this table (it sits below methods/), so it keeps its own list of reference
// lines; they must agree.
TEST(MethodTest, ReferenceColumnAgreesWithTheLeaderboards) {
  for (Method m : all_methods()) EXPECT_EQ(spec(m).reference, evaluator::is_reference_method(spec(m).name)) << spec(m).name;
}

TEST(MethodTest, WeightsNeededFollowTheRecipe) {
  for (Method m : all_methods()) {
    const Recipe& r = spec(m).recipe;
    EXPECT_EQ(r.needs_led_weights(), r.lens_detector) << spec(m).name;
    EXPECT_EQ(r.needs_aef_weights(), r.particle_filter && r.aef == restoration::aef::FilterMethod::kLearned) << spec(m).name;
  }
  EXPECT_TRUE(recipe(Method::kWeatherGS).needs_led_weights() && recipe(Method::kWeatherGS).needs_aef_weights());
  EXPECT_FALSE(recipe(Method::kAefTophat).needs_aef_weights());
  EXPECT_TRUE(recipe(Method::kDerainNerf).led_per_view);
}

TEST(MethodTest, DesplatDescriptionNamesItsDistractorCount) {
  EXPECT_NE(method_description(Method::kDesplat).find(std::to_string(kDesplatDistractorsPerView) + " per training view"),
            std::string::npos);
  EXPECT_EQ(recipe(Method::kDesplat).distractors_per_view, kDesplatDistractorsPerView);
}

// Snapshots are fractions of a run: each backend scores at the same point of its own length.
TEST(MethodTest, SnapshotFractionsResolvePerBackendLength) {
  const std::vector<RunFraction> f = {{500, 1000}, {250, 1000}, {500, 1000}, {1, 30000}};
  EXPECT_EQ(snapshot_iterations(f, 1000), (std::vector<int>{500, 250, 500, 1}));
  EXPECT_EQ(snapshot_iterations(f, 80), (std::vector<int>{40, 20, 40, 1}));  // never iteration 0
  EXPECT_EQ(snapshot_iterations({{999, 1000}}, 10), std::vector<int>{});     // at the end: the final point
  EXPECT_EQ(scored_snapshots(f, 80), (std::vector<int>{1, 20, 40}));
}

}  // namespace
}  // namespace weathergs::methods
