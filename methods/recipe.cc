#include "methods/recipe.h"

#include <filesystem>

#include "core/sha256.h"
#include "evaluator/evaluate.h"
#include "evaluator/lpips.h"
#include "nerf/numerics.h"
#include "reconstruction/numerics.h"
#include "reconstruction/run.h"
#include "restoration/led/lens_detector.h"

namespace weathergs::methods {

namespace fs = std::filesystem;

restoration::aef::FilterDatasetOptions aef_stage_options(const ReconstructOptions& o) {
  const Recipe& r = spec(o.method).recipe;
  restoration::aef::FilterDatasetOptions f;
  f.filter = o.particle_filter;
  f.method = r.aef;
  if (r.needs_aef_weights()) {
    f.task = restoration::aef::AefTask::kAuto;  // the selector decides, per scene, which plugin (or none)
    f.aef_weights = o.aef_weights;
  }
  return f;
}

restoration::led::DetectDatasetOptions led_stage_options(const ReconstructOptions& o) {
  restoration::led::DetectDatasetOptions d;
  d.weights = o.led_weights;
  d.mask = o.led_mask;
  if (spec(o.method).recipe.led_per_view) d.averaging = restoration::led::LedAveraging::kPerView;
  return d;
}

std::optional<adaptation::LedAdaptOptions> led_stage_adaptation(const ReconstructOptions& o) {
  // Per-view maps follow drops that move, so they are never adapted to drops fixed to the lens.
  return spec(o.method).recipe.led_per_view ? std::nullopt : o.led_adapt;
}

namespace {

// The sha256 a weights manifest records of its blob (restoration/torch_weights.h), as the AEF stage
// records it in filter.json.
std::string manifest_sha256(const fs::path& manifest) {
  if (!fs::is_regular_file(manifest)) throw InputError(manifest.string(), "missing: a weights manifest the method needs");
  return read_json_file(manifest.string()).value("weights_sha256", "");
}

// Where the trainer's points come from, as the dataset and the points policy decide it.
const char* points_source(const ReconstructOptions& o, const Dataset& ds) {
  if (dataset_has_points(ds, o.method)) return "dataset";
  return o.points == PointsPolicy::kAuto ? "triangulate" : "random";
}

Json scoring_record(const evaluator::ScoringOptions& scoring) {
  evaluator::EvaluateOptions e;  // a run scores its test split against clean/, unmasked
  e.scoring = scoring;
  Json s = evaluator::protocol_to_json(evaluator::scoring_protocol(e));
  s["lpips_sha256"] = scoring.lpips ? Json(sha256_file(evaluator::find_lpips_model(scoring.lpips_model_search))) : Json();
  return s;
}

// The recipe; without a dataset, the part every variant shares (no dataset, run_length, points).
Json build_recipe(const ReconstructOptions& o, const Dataset* ds, const std::string& dataset_sha256) {
  const MethodSpec& m = spec(o.method);
  const Recipe& r = m.recipe;
  const bool nerf = r.backend == BackendKind::kNerf;
  Json recipe{{"method", m.name},
              {"backend", nerf ? "nerf" : "3dgs"},
              {"numerics", nerf ? nerf::kFieldNumericsVersion : reconstruction::kTrainerNumericsVersion},
              {"scoring", scoring_record(o.scoring)}};
  if (ds) {
    recipe["points"] = points_source(o, *ds);
    recipe["dataset"] = dataset_sha256;
  }
  if (nerf) {
    Json n = o.nerf.to_json();
    n.erase("seed");
    recipe["options"] = n;
  } else {
    // The length and budget the dataset makes of the request go apart from the options: they differ
    // between variants under the fast schedule, while the rest must not.
    ReconstructOptions resolved = o;
    if (ds) resolved.train = reconstruction::run_length_for(o.train, *ds);
    Json t = method_train_options(resolved).to_json();
    if (ds) recipe["run_length"] = {{"iterations", t.at("iterations")}, {"max_gaussians", t.at("max_gaussians")}};
    for (const char* key : {"seed", "iterations", "max_gaussians"}) t.erase(key);
    recipe["options"] = t;
  }
  Json restoration = Json::object(), weights = Json::object();
  if (r.particle_filter)  // width 0: the top-hat's radius in pixels follows from the dataset
    restoration["aef"] = restoration::aef::filter_settings_json(aef_stage_options(o), 0);
  if (r.needs_aef_weights()) {
    Json aef = Json::object();
    for (const char* stem : {restoration::aef::kDerainStem, restoration::aef::kDesnowStem, restoration::aef::kSelectorStem})
      aef[stem] = manifest_sha256(fs::path(o.aef_weights) / (std::string(stem) + ".json"));
    weights["aef"] = aef;
  }
  if (r.lens_detector) {
    const restoration::led::DetectDatasetOptions d = led_stage_options(o);
    const std::optional<adaptation::LedAdaptOptions> adapt = led_stage_adaptation(o);
    restoration::led::LensDetector led = restoration::led::LensDetector::load(d.weights);
    if (adapt) restoration::led::use_adapted_peak_rule(led);
    const std::string sha = led.metadata().value(restoration::led::detect_key::kWeightsSha256, "");
    Json led_settings = restoration::led::detect_settings_json(sha, d, d.mask.resolved(led));
    led_settings.erase(restoration::led::detect_key::kWeightsSha256);
    if (adapt && !ds)
      throw InputError("--led-adapt", "the adaptation's length follows the dataset's training views: its recipe needs "
                                      "the dataset");
    led_settings[restoration::led::detect_key::kAdaptation] =
        adapt ? adaptation::adaptation_settings_json(*adapt, ds->split("train").size()) : Json();
    restoration["led"] = led_settings;
    weights["led"] = sha;
  }
  recipe["restoration"] = restoration;
  recipe["weights"] = weights;
  return recipe;
}

}  // namespace

Json run_recipe(const ReconstructOptions& options, const Dataset& dataset, const std::string& dataset_sha256) {
  return build_recipe(options, &dataset, dataset_sha256);
}

Json run_recipe_across_datasets(const ReconstructOptions& options) { return build_recipe(options, nullptr, ""); }

}  // namespace weathergs::methods
