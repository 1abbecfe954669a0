// A run's recipe (methods/recipe.h, evaluator/recipe.h): reconstruct records the recipe that
// run_recipe gives before any training, seeds share it, and each thing that makes another model
// (an option, a weight file, the dataset, the LED's rule, the backend) moves it under its own key; an
// archived run is restored for its recipe only.
// On the committed regression fixture (tests/data/regression/station_rain), ~10 s.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/dataset_identity.h"
#include "evaluator/archive.h"
#include "evaluator/recipe.h"
#include "methods/archive_restore.h"
#include "methods/recipe.h"
#include "methods/reconstruct.h"
#include "tests/core/test_util.h"

namespace weathergs::methods {
namespace {

namespace fs = std::filesystem;
using weathergs::testing::TempDir;

const std::string kFixture = std::string(WEATHERGS_SOURCE_DIR) + "/tests/data/regression/station_rain";

ReconstructOptions options(Method m, const std::string& out = "") {
  ReconstructOptions o;
  o.dataset = kFixture;
  o.out = out;
  o.method = m;
  o.train.iterations = 20;
  o.train.seed = 1;
  o.points = PointsPolicy::kDataset;
  o.scoring.lpips_model_search = weathergs::testing::lpips_model_search();
  o.led_weights = std::string(WEATHERGS_SOURCE_DIR) + "/models/led/led";
  o.aef_weights = std::string(WEATHERGS_SOURCE_DIR) + "/models/aef";
  return o;
}

std::string difference(const Json& a, const Json& b) {
  const auto d = evaluator::first_recipe_difference(a, b);
  return d ? d->key : "(none)";
}

TEST(RecipeTest, ReconstructRecordsTheRecipeKnownBeforeTrainingAndSeedsShareIt) {
  TempDir tmp;
  const Dataset ds = read_dataset(kFixture);
  const std::string sha = compute_dataset_identity(kFixture).sha256;
  ReconstructOptions o = options(Method::k3dgs, tmp / "run");
  const ReconstructResult r = reconstruct(o);
  const std::optional<evaluator::RecordedRecipe> recorded = evaluator::recorded_recipe(r.results, "results.json");
  ASSERT_TRUE(recorded);
  o.train.seed = 7;  // another seed of the same cell
  const Json before = run_recipe(o, ds, sha);
  EXPECT_EQ(recorded->recipe, before) << difference(recorded->recipe, before);
  EXPECT_EQ(recorded->fingerprint, evaluator::recipe_fingerprint(before));
  EXPECT_EQ(before.at("numerics"), "3dgs-numerics-1");
  EXPECT_EQ(before.at("run_length").at("iterations"), 20);
  EXPECT_FALSE(before.at("options").contains("seed"));
  EXPECT_EQ(before.at("dataset"), sha);
  EXPECT_EQ(before.at("scoring").at("lpips_sha256").get<std::string>().size(), 64u);
  EXPECT_EQ(r.results.method_info.at("threads").get<int>() >= 1, true);
  // The eval points and the checkpoint interval make the same model: the same recipe.
  ReconstructOptions same = o;
  same.eval_at = {5, 10};
  same.checkpoint_every = 3;
  EXPECT_EQ(run_recipe(same, ds, sha), before);
  // Archived, the run is restored for the same recipe and any --out, byte for byte, and for nothing else.
  evaluator::ArchiveAddOptions add;
  add.run_dir = tmp / "run";
  add.suite_dir = tmp / "archive/t";
  ASSERT_EQ(evaluator::archive_add(add).outcome, evaluator::ArchiveAddResult::Outcome::kAdded);
  ReconstructOptions again = options(Method::k3dgs, tmp / "again");
  const RestoreOutcome restored = restore_from_archive(again, add.suite_dir);
  EXPECT_TRUE(restored.restored) << restored.why;
  EXPECT_EQ(read_file(tmp / "again/results.json"), read_file(tmp / "run/results.json"));
  EXPECT_FALSE(fs::exists(tmp / "again/model"));
  EXPECT_THROW(restore_from_archive(again, add.suite_dir), InputError);  // a complete run is not replaced
  again.force = true;
  EXPECT_TRUE(restore_from_archive(again, add.suite_dir).restored);
  ReconstructOptions other = options(Method::k3dgs, tmp / "other");
  other.train.densify_until = 900;
  const RestoreOutcome stale = restore_from_archive(other, add.suite_dir);
  EXPECT_FALSE(stale.restored);
  EXPECT_NE(stale.why.find("options/densify_until: 15000 vs 900"), std::string::npos) << stale.why;
  other = options(Method::k3dgs, tmp / "other");
  other.train.seed = 2;
  EXPECT_NE(restore_from_archive(other, add.suite_dir).why.find("no run archived in"), std::string::npos);
  EXPECT_FALSE(fs::exists(tmp / "other"));
  // A record whose fingerprint no longer matches its recipe was edited: refused, naming the file.
  evaluator::Results edited = r.results;
  edited.method_info["recipe"]["options"]["densify_until"] = 1;
  EXPECT_THROW(evaluator::recorded_recipe(edited, "edited.json"), InputError);
}

TEST(RecipeTest, EachIngredientMovesItsOwnKey) {
  TempDir tmp;
  const Dataset ds = read_dataset(kFixture);
  const std::string sha = compute_dataset_identity(kFixture).sha256;
  const ReconstructOptions o = options(Method::kWeatherGS);
  const Json base = run_recipe(o, ds, sha);
  EXPECT_EQ(base.at("weights").at("led").get<std::string>().size(), 64u);
  EXPECT_EQ(base.at("weights").at("aef").size(), 3u);

  ReconstructOptions t = o;
  t.train.densify_until = 900;
  EXPECT_EQ(difference(base, run_recipe(t, ds, sha)), "options/densify_until");
  t = o;
  t.train.iterations = 40;
  EXPECT_EQ(difference(base, run_recipe(t, ds, sha)), "run_length/iterations");
  EXPECT_EQ(difference(evaluator::recipe_across_datasets(base), evaluator::recipe_across_datasets(run_recipe(t, ds, sha))),
            "(none)");
  EXPECT_EQ(difference(base, run_recipe(o, ds, std::string(64, '0'))), "dataset");
  // Without a dataset: exactly the part every variant shares.
  EXPECT_EQ(run_recipe_across_datasets(o), evaluator::recipe_across_datasets(base));
  t = o;
  t.led_mask.rule = restoration::led::LedThresholdRule::kAbove;
  t.led_mask.threshold = 0.3;
  EXPECT_EQ(difference(base, run_recipe(t, ds, sha)), "restoration/led/peak_rule");
  t = o;
  t.scoring.lpips = false;
  EXPECT_EQ(difference(base, run_recipe(t, ds, sha)), "scoring/lpips");
  // Other AEF weights (the same files but one manifest's blob hash): the weights' key.
  fs::copy(o.aef_weights, tmp / "aef");
  Json manifest = read_json_file(tmp / "aef/derain.json");
  manifest["weights_sha256"] = std::string(64, 'a');
  write_file_atomic(tmp / "aef/derain.json", manifest.dump(2));
  t = o;
  t.aef_weights = tmp / "aef";
  EXPECT_EQ(difference(base, run_recipe(t, ds, sha)), "weights/aef/derain");
  // The same weights in another folder are the same recipe.
  fs::copy(o.aef_weights + "/derain.json", tmp / "aef/derain.json", fs::copy_options::overwrite_existing);
  EXPECT_EQ(run_recipe(t, ds, sha), base);
  // Another method: its name, and what it runs.
  EXPECT_EQ(difference(base, run_recipe(options(Method::kWeatherGSNoLed), ds, sha)), "method");
}

TEST(RecipeTest, RadianceFieldRecipeHasItsNumericsAndNoSeed) {
  const Dataset ds = read_dataset(kFixture);
  ReconstructOptions o = options(Method::kNerf);
  const Json a = run_recipe(o, ds, "x");
  EXPECT_EQ(a.at("backend"), "nerf");
  EXPECT_EQ(a.at("numerics"), "nerf-numerics-1");
  EXPECT_FALSE(a.contains("run_length"));
  EXPECT_FALSE(a.at("options").contains("seed"));
  o.train.seed = 5;
  o.nerf.seed = 9;
  o.train.iterations = 999;  // the 3DGS length is only the unit of --eval-at for a radiance field
  EXPECT_EQ(run_recipe(o, ds, "x"), a);
  o.nerf.tv_density = 0.5;
  EXPECT_EQ(difference(a, run_recipe(o, ds, "x")), "options/tv_density");
}

}  // namespace
}  // namespace weathergs::methods
