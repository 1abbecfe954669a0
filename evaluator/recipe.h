// The recipe of a run, as results.json's method_info records it (docs/archive.md, "The recipe"):
// everything that decides a run's trained bits and its scores except its seed, and its fingerprint,
// the sha256 of the recipe's canonical JSON. Runs with one fingerprint are comparable; the seeds of
// one cell share it. methods/ writes the recipe (methods/recipe.h); this is the reader's side, for
// the leaderboard, the report and the results archive.
//
// The recipe's top-level keys: method, backend, numerics (the backend's trainer-numerics version),
// options (the trainer's options as requested, without the seed), run_length (3DGS: what the
// dataset made of the requested length and budget), points, restoration (the AEF's and the LED's
// settings, for the methods that run them), weights (sha256 of every weight file), dataset (the
// dataset identity's sha256) and scoring (the protocol and the LPIPS weights' sha256).
#pragma once

#include <optional>
#include <string>

#include "core/json_reader.h"
#include "evaluator/results.h"

namespace weathergs::evaluator {

inline constexpr const char* kRecipeKey = "recipe";                         // method_info.recipe
inline constexpr const char* kRecipeFingerprintKey = "recipe_fingerprint";  // method_info.recipe_fingerprint

// The sha256 of recipe.dump(): nlohmann's objects are ordered by key and its numbers print the same
// for the same value, so equal recipes give equal text.
std::string recipe_fingerprint(const Json& recipe);

// The first place two recipes differ, as a key path ("options/densify_until", "weights/led",
// "dataset") with both values (null where one side lacks the key, written "none"); keys in byte order.
struct RecipeDifference {
  std::string key;
  Json a, b;
  std::string to_string() const;  // "options/densify_until: 15000 vs 7000"
};
std::optional<RecipeDifference> first_recipe_difference(const Json& a, const Json& b);

// The recipe without the keys that hold what its dataset made of it (dataset, run_length, points:
// whether the dataset held the SfM points): what every run of one method shares across variants and
// seeds.
Json recipe_across_datasets(const Json& recipe);

struct RecordedRecipe {
  Json recipe;
  std::string fingerprint;
};
// The recipe a result records, or nullopt when it records none (results made before recipes).
// InputError naming `where` when only one of recipe and fingerprint is there, or the fingerprint is
// not the recipe's (an edited record).
std::optional<RecordedRecipe> recorded_recipe(const Results& results, const std::string& where);

}  // namespace weathergs::evaluator
