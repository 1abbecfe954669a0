// find_mixed_recipes (leaderboard.h): which results of a leaderboard were made with another recipe
// than the rest of their group.
#include <algorithm>
#include <functional>
#include <initializer_list>
#include <map>

#include "evaluator/leaderboard.h"
#include "evaluator/recipe.h"

namespace weathergs::evaluator {

namespace {

// One rule: how results are grouped, the part of their recipes that must agree within a group, and
// how a group is named in messages.
struct Rule {
  std::function<std::string(const Results&, const Json&)> group;  // "" = not in any group
  std::function<Json(const Json&)> part;
  std::string what;  // what the group's runs share: "the LPIPS weights", ...
};

std::string variant_of(const Results& r) {
  const std::string scene = r.scene.empty() ? r.dataset : r.scene;
  return r.weather.empty() ? scene : scene + " " + r.weather;
}

// The protocol itself is each table's to check (build_leaderboard), so the rules leave "scoring" out
// but for the LPIPS weights.
Json without(Json r, std::initializer_list<const char*> keys) {
  if (r.is_object())
    for (const char* k : keys) r.erase(k);
  return r;
}

std::vector<Rule> rules() {
  return {
      // Results that record no recipe (a method of one's own, scored by `evaluate`) are judged within
      // their method only.
      {[](const Results&, const Json& r) { return r.is_null() ? std::string() : std::string("every run"); },
       [](const Json& r) { return r.contains("scoring") ? r.at("scoring").value("lpips_sha256", Json()) : Json(); },
       "the LPIPS weights"},
      {[](const Results&, const Json& r) { return r.is_null() ? std::string() : "backend " + r.value("backend", "?"); },
       [](const Json& r) { return r.value("numerics", Json()); }, "the trainer-numerics version"},
      {[](const Results& res, const Json&) { return res.method; },
       [](const Json& r) { return without(recipe_across_datasets(r), {"scoring"}); },
       "the recipe but what their datasets make of it"},
      // find_mixed_data judges the dataset.
      {[](const Results& res, const Json&) { return res.method + " on " + variant_of(res); },
       [](const Json& r) { return without(r, {"dataset", "scoring"}); }, "the recipe but the dataset's identity"},
  };
}

// How a group's part is named in notes: a value as it is (a sha256 by its first 12 hex digits), a
// recipe by the first 12 hex digits of its own sha256.
std::string short_fingerprint(const Json& part) {
  if (part.is_null()) return "none recorded";
  if (part.is_string()) return part.get<std::string>().substr(0, 15);
  return "recipe " + recipe_fingerprint(part).substr(0, 12);
}

}  // namespace

std::vector<std::string> MixedRecipes::notes(const std::string& weather) const {
  std::vector<std::string> out;
  for (const Group& g : groups)
    if (weather.empty() || g.weathers.count(weather)) out.push_back(g.note);
  return out;
}

std::string other_recipe_note(const std::vector<std::string>& lines) {
  if (lines.empty()) return "";
  std::string o = std::string(kOtherRecipeMarker) +
                  " Includes runs made with another recipe than the rest of their group, or with none recorded "
                  "(the recipes by the first 12 hex digits of their parts' sha256): ";
  for (size_t i = 0; i < lines.size(); ++i) o += (i ? "; " : "") + lines[i];
  return o + ".";
}

std::string cell_marks(const CellStats& c) {
  return std::string(c.other_data ? kOtherDataMarker : "") + (c.other_recipe ? kOtherRecipeMarker : "");
}

MixedRecipes find_mixed_recipes(const std::vector<LoadedResults>& results, const LeaderboardOptions& options) {
  std::vector<Json> recipes;  // per result: its recipe, null when it records none
  for (const LoadedResults& lr : results) {
    const std::optional<RecordedRecipe> r = recorded_recipe(lr.results, lr.path);
    recipes.push_back(r ? r->recipe : Json());
  }
  MixedRecipes out;
  for (const Rule& rule : rules()) {
    std::vector<std::string> order;
    std::map<std::string, std::vector<size_t>> groups;
    for (size_t i = 0; i < results.size(); ++i) {
      const std::string g = rule.group(results[i].results, recipes[i]);
      if (g.empty()) continue;
      if (!groups.count(g)) order.push_back(g);
      groups[g].push_back(i);
    }
    for (const std::string& g : order) {
      std::vector<std::string> parts;  // distinct parts by their dump, first appearance
      std::map<std::string, int> count;
      std::map<std::string, size_t> first;
      for (size_t i : groups[g]) {
        const std::string key = recipes[i].is_null() ? "" : rule.part(recipes[i]).dump();
        if (count[key]++ == 0) {
          parts.push_back(key);
          first[key] = i;
        }
      }
      if (parts.size() < 2) continue;  // one recipe, or none recorded by any
      std::string ref;
      for (const std::string& p : parts)
        if (!p.empty() && (ref.empty() || count[p] > count[ref])) ref = p;
      const size_t on_ref = first[ref];
      const Json ref_part = rule.part(recipes[on_ref]);
      MixedRecipes::Group group;
      group.note = g + ": " + std::to_string(count[ref]) + " on " + short_fingerprint(ref_part) + " (the group's)";
      for (const std::string& p : parts) {
        if (p == ref) continue;
        const size_t i = first[p];
        const Json part = p.empty() ? Json() : rule.part(recipes[i]);
        const std::string why = p.empty() ? "records no recipe (made before runs recorded one)"
                                          : "made with another recipe (" +
                                                first_recipe_difference(part, ref_part)->to_string() + ")";
        group.note += "; " + std::to_string(count[p]) + " on " + short_fingerprint(part) +
                      (p.empty() ? "" : " (" + first_recipe_difference(part, ref_part)->key + ")");
        if (!options.allow_mixed_recipes)
          throw InputError(results[i].path, why + " than " + results[on_ref].path + " (" + g + ": its runs share " +
                                                rule.what + "): runs of other recipes cannot share a leaderboard; run "
                                                "them again with one recipe, or pass --allow-mixed-recipes to mark them");
      }
      for (size_t i : groups[g]) {
        if (recipes[i].is_null() ? ref.empty() : rule.part(recipes[i]).dump() == ref) continue;
        out.odd.insert(&results[i]);
        group.weathers.insert(results[i].results.weather);
      }
      out.groups.push_back(group);
    }
  }
  return out;
}

}  // namespace weathergs::evaluator
