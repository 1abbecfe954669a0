#include "methods/method.h"

#include <string>

#include "core/error.h"

namespace weathergs::methods {

namespace {

using reconstruction::TrainImages;
using reconstruction::TrainMasks;
using restoration::aef::FilterMethod;

// Recipe builders, so that each row of the table below states only what sets its method apart.
constexpr Recipe clean(Recipe r) {
  r.images = TrainImages::kClean;
  r.clean_points = true;
  return r;
}
constexpr Recipe field(Recipe r) {
  r.backend = BackendKind::kNerf;
  return r;
}
constexpr Recipe aef(Recipe r, FilterMethod m = FilterMethod::kLearned) {
  r.particle_filter = true;
  r.aef = m;
  return r;
}
constexpr Recipe led(Recipe r, bool per_view = false) {
  r.lens_detector = true;
  r.led_per_view = per_view;
  return r;
}
constexpr Recipe gt_masks() {
  Recipe r;
  r.masks = TrainMasks::kAll;
  return r;
}
constexpr Recipe robust() {
  Recipe r;
  r.robust = true;
  return r;
}
constexpr Recipe distractors(int per_view) {
  Recipe r;
  r.distractors_per_view = per_view;
  return r;
}
constexpr Recipe in_the_wild() {
  Recipe r;
  r.in_the_wild = true;
  return r;
}

// The desplat description names kDesplatDistractorsPerView; tests/methods checks that they agree.
constexpr MethodSpec kMethods[] = {
    {Method::k3dgs, "3dgs", "vanilla 3DGS on the weathered images", Recipe{}, false},
    {Method::kOracle, "oracle", "3DGS on the clean images and their SfM points (upper bound)", clean({}), true},
    {Method::kGtMasks, "gt-masks",
     "3DGS on the weathered images, ground-truth particle and lens masks excluded from the loss", gt_masks(), true},
    {Method::kAefTophat, "aef-tophat",
     "classical particle filter (morphological top-hat) on every view, then 3DGS", aef({}, FilterMethod::kTopHat),
     false},
    {Method::kWeatherGS, "weathergs",
     "WeatherGS: AEF (learned derain/desnow plugin chosen by the weather selector) on every view, LED on the "
     "raw views averaged over the training views, 3DGS on the filtered images with the LED mask excluded",
     led(aef({})), false},
    {Method::kWeatherGSNoAef, "weathergs-no-aef",
     "WeatherGS without the AEF: LED on the raw views, masked 3DGS on the raw images", led({}), false},
    {Method::kWeatherGSNoLed, "weathergs-no-led",
     "WeatherGS without the LED: AEF (learned, selector) on every view, then 3DGS", aef({}), false},
    {Method::kRobust3dgs, "robust-3dgs",
     "3DGS with the RobustFilter distractor mask (SpotLessSplats' robust baseline: pixels above the running "
     "70th-percentile error excluded from the loss, annealed), no opacity reset",
     robust(), false},
    {Method::kDesplat, "desplat",
     "3DGS with DeSplat-style distractor Gaussians: 1000 per training view in front of its camera, rendered only "
     "for that view, dropped at test time",
     distractors(kDesplatDistractorsPerView), false},
    {Method::kGsWLite, "gs-w-lite",
     "GS-W-style 3DGS in the wild without a pretrained encoder: per-view affine appearance (identity at test "
     "time) and a learned per-view visibility map with GS-W's (1 - M)^2 regulariser",
     in_the_wild(), false},
    {Method::kNerf, "nerf", "grid radiance field (DVGO/Plenoxels family, docs/nerf.md) on the weathered images",
     field({}), false},
    {Method::kDerainNerf, "derainnerf",
     "DerainNeRF: LED attention per view (not averaged) as occlusion masks excluded from the radiance field's MSE",
     led(field({}), true), false},
    {Method::kWeatherGSNerf, "weathergs-nerf",
     "Ours-NeRF: AEF (learned, selector) on every view, LED averaged over the training views, radiance field "
     "with the LED mask excluded",
     led(aef(field({}))), false},
    {Method::kNerfOracle, "nerf-oracle", "grid radiance field on the clean images (its upper bound)",
     clean(field({})), true},
};

// The table is indexed by the enum: a row out of place is a build error, not a wrong recipe.
constexpr bool rows_in_enum_order() {
  for (size_t i = 0; i < sizeof kMethods / sizeof kMethods[0]; ++i)
    if (static_cast<size_t>(kMethods[i].method) != i) return false;
  return true;
}
static_assert(rows_in_enum_order(), "kMethods must list the methods in the order of enum Method");
static_assert(sizeof kMethods / sizeof kMethods[0] == static_cast<size_t>(Method::kNerfOracle) + 1,
              "kMethods must have one row per method");

}  // namespace

const MethodSpec& spec(Method m) {
  const size_t i = static_cast<size_t>(m);
  WGS_CHECK(i < sizeof kMethods / sizeof kMethods[0]);
  return kMethods[i];
}

const char* to_string(Method m) { return spec(m).name; }

std::vector<Method> all_methods() {
  std::vector<Method> out;
  for (const MethodSpec& s : kMethods) out.push_back(s.method);
  return out;
}

Method parse_method(const std::string& name, const std::string& where) {
  std::string known;
  for (const MethodSpec& s : kMethods) {
    if (name == s.name) return s.method;
    known += (known.empty() ? "" : ", ") + std::string(s.name);
  }
  throw InputError(where, "unknown method \"" + name + "\" (known: " + known + ")");
}

std::string method_description(Method m) { return spec(m).description; }

Recipe recipe(Method m) { return spec(m).recipe; }

}  // namespace weathergs::methods
