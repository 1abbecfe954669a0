#include "evaluator/recipe.h"

#include <set>

#include "core/sha256.h"

namespace weathergs::evaluator {

std::string recipe_fingerprint(const Json& recipe) { return sha256_hex(recipe.dump()); }

std::string RecipeDifference::to_string() const {
  auto text = [](const Json& v) { return v.is_null() ? std::string("none") : v.dump(); };
  return key + ": " + text(a) + " vs " + text(b);
}

std::optional<RecipeDifference> first_recipe_difference(const Json& a, const Json& b) {
  if (a == b) return std::nullopt;
  if (!a.is_object() || !b.is_object()) return RecipeDifference{"", a, b};
  std::set<std::string> keys;
  for (const auto& [k, v] : a.items()) keys.insert(k);
  for (const auto& [k, v] : b.items()) keys.insert(k);
  for (const std::string& k : keys) {
    const Json va = a.contains(k) ? a.at(k) : Json(), vb = b.contains(k) ? b.at(k) : Json();
    if (std::optional<RecipeDifference> d = first_recipe_difference(va, vb)) {
      d->key = d->key.empty() ? k : k + "/" + d->key;
      return d;
    }
  }
  return std::nullopt;
}

Json recipe_across_datasets(const Json& recipe) {
  Json r = recipe;
  if (r.is_object()) {
    for (const char* key : {"dataset", "run_length", "points"}) r.erase(key);
  }
  return r;
}

std::optional<RecordedRecipe> recorded_recipe(const Results& results, const std::string& where) {
  const Json& info = results.method_info;
  const bool has_recipe = info.contains(kRecipeKey), has_fingerprint = info.contains(kRecipeFingerprintKey);
  if (!has_recipe && !has_fingerprint) return std::nullopt;
  if (has_recipe != has_fingerprint)
    throw InputError(where + ":/method_info", std::string("records ") + (has_recipe ? kRecipeKey : kRecipeFingerprintKey) +
                                                  " without " + (has_recipe ? kRecipeFingerprintKey : kRecipeKey) +
                                                  ": a run's recipe and its fingerprint are written together");
  const Json& recipe = info.at(kRecipeKey);
  const Json& fingerprint = info.at(kRecipeFingerprintKey);
  if (!recipe.is_object()) throw InputError(where + ":/method_info/recipe", "expected an object");
  if (!fingerprint.is_string()) throw InputError(where + ":/method_info/recipe_fingerprint", "expected a sha256 string");
  const std::string computed = recipe_fingerprint(recipe);
  if (computed != fingerprint.get<std::string>())
    throw InputError(where + ":/method_info/recipe_fingerprint",
                     "is " + fingerprint.get<std::string>() + ", but the recipe beside it hashes to " + computed +
                         ": the record was edited; re-run it, or restore it from the archive");
  return RecordedRecipe{recipe, computed};
}

}  // namespace weathergs::evaluator
