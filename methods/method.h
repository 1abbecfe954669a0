// The reconstruction methods of the benchmark, one recipe each (docs/methods.md). A recipe says what a
// method trains on: which images, which loss masks, which SfM points. Methods that need the
// restoration part: the Atmospheric Effect Filter (the learned derain/desnow plugins chosen by the
// weather selector, or the classical top-hat) and the learned Lens Effect Detector. Methods run on one
// of two backends: 3DGS (reconstruction/) or the grid radiance field (nerf/).
#pragma once

#include <string>
#include <vector>

#include "reconstruction/run.h"
#include "restoration/aef/filter_dataset.h"

namespace weathergs::methods {

enum class Method {
  k3dgs,     // vanilla 3DGS on the weathered images (the paper's baseline)
  kOracle,   // 3DGS on the clean images and their SfM points: the upper bound
  kGtMasks,  // 3DGS on the weathered images with the generator's particle and lens masks excluded
  kAefTophat,  // the classical AEF (restoration/aef/particle_filter.h) on every view, then 3DGS on the
               // filtered images: WeatherGS's first stage without learned weights and without the LED
  kWeatherGS,       // AEF (learned plugins, selector on the scene) -> LED on the filtered views, averaged
                    // over the training views -> 3DGS on the filtered images, LED mask excluded from the loss
  kWeatherGSNoAef,  // ablation (the paper's Table III): LED on the raw views, 3DGS on the raw images, masked
  kWeatherGSNoLed,  // ablation: the learned AEF only
  kRobust3dgs,      // 3DGS with the RobustFilter per-pixel distractor mask (reconstruction/robust_mask.h)
  kDesplat,         // 3DGS with per-view distractor Gaussians, dropped at test time (reconstruction/distractors.h)
  kGsWLite,         // GS-W-style 3DGS in the wild without its encoder (reconstruction/in_the_wild.h)
  // The radiance-field backend (nerf/, docs/nerf.md): the paper's NeRF-family rows.
  kNerf,           // the grid radiance field on the weathered images (the paper's NeRF row)
  kDerainNerf,     // DerainNeRF: per-view LED masks (not averaged) excluded from the radiance field's MSE
  kWeatherGSNerf,  // "Ours-NeRF" (Table IV): the WeatherGS preprocessing (AEF -> LED averaged) on the field
  kNerfOracle,     // the radiance field on the clean images: its upper bound
};
// Distractor Gaussians per training view of the desplat method: enough footprints to cover a view
// once (radius ~4 px at 300x200, distractors.h) and few next to a scene of 10^4-10^5 Gaussians. Set
// before any benchmark run, not tuned on it.
constexpr int kDesplatDistractorsPerView = 1000;

// Which reconstruction a method trains: 3DGS (reconstruction/) or the radiance field (nerf/).
enum class BackendKind { k3dgs, kNerf };

struct Recipe {
  BackendKind backend = BackendKind::k3dgs;
  reconstruction::TrainImages images = reconstruction::TrainImages::kImages;
  reconstruction::TrainMasks masks = reconstruction::TrainMasks::kNone;
  bool clean_points = false;  // initialize from sparse_clean/0 (clean/ triangulated) instead of sparse/0
  bool particle_filter = false;  // train on the AEF's restored images (RUN/filtered/)
  // Which AEF: the learned derain/desnow plugins with the weather selector deciding per scene (the
  // better one on the benchmark, docs/restoration.md), or the classical top-hat on every view.
  restoration::aef::FilterMethod aef = restoration::aef::FilterMethod::kLearned;
  // Exclude the LED's mask (RUN/detected/) from the loss. The LED always looks at the raw views:
  // on the learned AEF's output it masked 44.5% of pool_rain (IoU 0.22 with the true drops) against
  // 16.6% (IoU 0.41) on the top-hat's, because the plugins' smoothed regions read as defocused
  // drops to its sharpness cue (docs/methods.md); the paper runs it after the AEF.
  bool lens_detector = false;
  bool led_per_view = false;     // the LED's per-view maps instead of the mean over the training views
  bool robust = false;           // the trainer's RobustFilter mask (TrainOptions::Robust::kRobustFilter)
  int distractors_per_view = 0;  // TrainOptions::distractors_per_view (desplat)
  bool in_the_wild = false;      // TrainOptions::in_the_wild (gs-w-lite)

  // The weight files the method needs: the LED's stem, the learned AEF's folder.
  constexpr bool needs_led_weights() const { return lens_detector; }
  constexpr bool needs_aef_weights() const { return particle_filter && aef == restoration::aef::FilterMethod::kLearned; }
};

// One row per method: everything the program knows about it has this one home.
struct MethodSpec {
  Method method;
  const char* name;         // the --method name, results.json's "method"
  const char* description;  // results.json's method_info.method_description and the --method help
  Recipe recipe;
  // A reference line rather than a competitor (oracles, ground-truth masks): never bolded, listed
  // last (evaluator/leaderboard.h is_reference_method, which tests/methods checks against this column).
  bool reference;
};

const MethodSpec& spec(Method m);
const char* to_string(Method m);
std::vector<Method> all_methods();
// InputError naming `where` and the known names.
Method parse_method(const std::string& name, const std::string& where);
std::string method_description(Method m);
Recipe recipe(Method m);

}  // namespace weathergs::methods
