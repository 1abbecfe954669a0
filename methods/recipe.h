// A run's recipe before it runs (evaluator/recipe.h says what it holds, docs/archive.md why): built
// from the options `reconstruct` is given and the dataset, without training, so that `reconstruct`
// records it in results.json and `archive restore` asks the results archive for the same recipe.
//
// What the recipe leaves out, because it cannot change the trained bits or the scores: the seed (the
// cell's seeds share a recipe), eval_at / eval_fractions (snapshots are copies of the model, scored
// after training), checkpoint_every and force (a resumed run ends in the same bits), the COLMAP and
// LPIPS executables' and files' paths (the LPIPS weights count by their sha256), and the thread
// count (every stage gives the same bits on any number of threads).
#pragma once

#include <optional>
#include <string>

#include "adaptation/led_adaptation.h"
#include "core/dataset.h"
#include "core/json_reader.h"
#include "methods/reconstruct.h"
#include "restoration/aef/filter_dataset.h"
#include "restoration/led/detect_dataset.h"

namespace weathergs::methods {

// The recipe of a run of `options` (as given to reconstruct; the seed is not read) on `dataset`,
// whose files hash to the identity `dataset_sha256`. Reads the weights' manifests, loads the LED
// when the method runs it (its calibrated mask rule is part of the recipe) and hashes the LPIPS
// weights; trains nothing. InputError when a weight file the method needs is missing.
Json run_recipe(const ReconstructOptions& options, const Dataset& dataset, const std::string& dataset_sha256);
// The part of it that every variant shares, without a dataset: evaluator::recipe_across_datasets of
// run_recipe. InputError for a run that adapts the LED (the adaptation's length follows the dataset).
Json run_recipe_across_datasets(const ReconstructOptions& options);

// The options of the AEF stage (methods with the particle filter), the LED stage and its adaptation
// (methods with the LED; nullopt: the weights as they are): one home for the stages and the recipe.
restoration::aef::FilterDatasetOptions aef_stage_options(const ReconstructOptions& options);
restoration::led::DetectDatasetOptions led_stage_options(const ReconstructOptions& options);
std::optional<adaptation::LedAdaptOptions> led_stage_adaptation(const ReconstructOptions& options);

}  // namespace weathergs::methods
