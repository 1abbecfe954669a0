// TrainOptions: validation, the run-length-scaled schedule (effective()) and the JSON round trip.
// Split from trainer.cc, which keeps the optimisation itself.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.h"
#include "core/json_fields.h"
#include "reconstruction/resolution.h"
#include "reconstruction/trainer.h"

namespace weathergs::reconstruction {

void TrainOptions::validate(const std::string& where) const {
  auto fail = [&](const std::string& field, const std::string& value, const std::string& rule) {
    throw InputError(where, field + " = " + value + ": " + rule);
  };
  auto positive = [&](const char* name, double v) {
    if (!(v > 0) || !std::isfinite(v)) fail(name, std::to_string(v), "must be a positive finite number");
  };
  if (iterations < 0) fail("iterations", std::to_string(iterations), "must be >= 1, or 0 for the schedule's length");
  positive("position_lr_init", position_lr_init);
  positive("position_lr_final", position_lr_final);
  positive("feature_lr", feature_lr);
  positive("opacity_lr", opacity_lr);
  positive("scaling_lr", scaling_lr);
  positive("rotation_lr", rotation_lr);
  positive("adam_eps", adam_eps);
  positive("percent_dense", percent_dense);
  positive("densify_grad_threshold", densify_grad_threshold);
  positive("max_world_size", max_world_size);
  if (max_gaussians < 1) fail("max_gaussians", std::to_string(max_gaussians), "must be >= 1");
  if (!(lambda_dssim >= 0 && lambda_dssim <= 1)) fail("lambda_dssim", std::to_string(lambda_dssim), "must be in [0, 1]");
  if (!(adam_beta1 >= 0 && adam_beta1 < 1)) fail("adam_beta1", std::to_string(adam_beta1), "must be in [0, 1)");
  if (!(adam_beta2 >= 0 && adam_beta2 < 1)) fail("adam_beta2", std::to_string(adam_beta2), "must be in [0, 1)");
  if (max_sh_degree < 0 || max_sh_degree > kMaxShDegree)
    fail("max_sh_degree", std::to_string(max_sh_degree), "must be in [0, 3]");
  if (sh_degree_interval < 1) fail("sh_degree_interval", std::to_string(sh_degree_interval), "must be >= 1");
  if (densification_interval < 1)
    fail("densification_interval", std::to_string(densification_interval), "must be >= 1");
  if (large_prune_from < 0) fail("large_prune_from", std::to_string(large_prune_from), "must be >= 0");
  if (opacity_reset_interval < 1)
    fail("opacity_reset_interval", std::to_string(opacity_reset_interval), "must be >= 1");
  if (position_lr_hold_until < 0)
    fail("position_lr_hold_until", std::to_string(position_lr_hold_until), "must be >= 0");
  for (size_t k = 0; k < blend_prune_at.size(); ++k)
    if (blend_prune_at[k] < 1 || (k > 0 && blend_prune_at[k] <= blend_prune_at[k - 1]))
      fail("blend_prune_at[" + std::to_string(k) + "]", std::to_string(blend_prune_at[k]),
           "iterations must be >= 1 and strictly ascending");
  if (!(blend_prune_threshold > 0 && blend_prune_threshold < 1))
    fail("blend_prune_threshold", std::to_string(blend_prune_threshold), "must be in (0, 1)");
  if (!(min_opacity >= 0 && min_opacity < 1)) fail("min_opacity", std::to_string(min_opacity), "must be in [0, 1)");
  for (int c = 0; c < 3; ++c)
    if (!(background[c] >= 0 && background[c] <= 1))
      fail("background", std::to_string(background[c]), "each channel must be in [0, 1]");
  if (distractors_per_view < 0 || distractors_per_view > 100000)
    fail("distractors_per_view", std::to_string(distractors_per_view), "must be in [0, 100000]");
  if (in_the_wild_from < 0) fail("in_the_wild_from", std::to_string(in_the_wild_from), "must be >= 0");
  if (!(visibility_weight >= 0 && std::isfinite(visibility_weight)))
    fail("visibility_weight", std::to_string(visibility_weight), "must be a finite number >= 0");
  if (!(distractor_opacity_weight >= 0 && std::isfinite(distractor_opacity_weight)))
    fail("distractor_opacity_weight", std::to_string(distractor_opacity_weight), "must be a finite number >= 0");
  if (!is_downsample_factor(downsample_start))
    fail("downsample_start", std::to_string(downsample_start), "must be 1, 2, 4, 8 or 16");
  if ((in_the_wild || robust != Robust::kNone) && downsample_start > 1)
    fail("downsample_start", std::to_string(downsample_start),
         "gs-w-lite and robust-3dgs train at full resolution: their visibility maps and distractor masks are "
         "defined per full-resolution pixel");
  if (!(full_resolution_at > 0 && full_resolution_at <= 1))
    fail("full_resolution_at", std::to_string(full_resolution_at), "must be in (0, 1]: every run ends at full resolution");
  if (random_init_count < 1) fail("random_init_count", std::to_string(random_init_count), "must be >= 1");
  if (!(random_init_near_m > 0 && random_init_far_m > random_init_near_m && std::isfinite(random_init_far_m)))
    fail("random_init_near_m/far_m", std::to_string(random_init_near_m) + "/" + std::to_string(random_init_far_m),
         "need 0 < near < far < inf");
}

namespace {

using namespace json_fields;
using Schedule = TrainOptions::Schedule;
using LargePrune = TrainOptions::LargePrune;
using RandomInit = TrainOptions::RandomInit;
using Robust = TrainOptions::Robust;

// The one list of TrainOptions' JSON keys (run.json, checkpoints); a missing key keeps its default.
constexpr auto kFields = [](auto& s, auto& f) {
  f("iterations", s.iterations);
  f("seed", s.seed);
  f("lambda_dssim", s.lambda_dssim);
  f("position_lr_init", s.position_lr_init);
  f("position_lr_final", s.position_lr_final);
  // The fields of the compressed schedule are written only when set, so that every record and
  // checkpoint of the other schedules keeps its bytes.
  f("position_lr_hold_until", s.position_lr_hold_until, OmitIf{0});
  f("feature_lr", s.feature_lr);
  f("opacity_lr", s.opacity_lr);
  f("scaling_lr", s.scaling_lr);
  f("rotation_lr", s.rotation_lr);
  f("adam_beta1", s.adam_beta1);
  f("adam_beta2", s.adam_beta2);
  f("adam_eps", s.adam_eps);
  f("max_sh_degree", s.max_sh_degree);
  f("sh_degree_interval", s.sh_degree_interval);
  f("percent_dense", s.percent_dense);
  f("densify_from", s.densify_from);
  f("densify_until", s.densify_until);
  f("densification_interval", s.densification_interval);
  f("densify_grad_threshold", s.densify_grad_threshold);
  f("opacity_reset_interval", s.opacity_reset_interval);
  f.custom(
      "blend_prune_at",
      [&] { return s.blend_prune_at.empty() ? Json(Json::value_t::discarded) : Json(s.blend_prune_at); },
      [&](const JsonReader& r, const std::string& k) {
        r.mark(k);
        if (!r.has(k)) return;
        const JsonReader a = r.child(k);
        if (!a.is_array()) throw InputError(a.where(), "expected an array of iterations");
        s.blend_prune_at.clear();
        for (size_t i = 0; i < a.size(); ++i) s.blend_prune_at.push_back(a.at(i).as<int>());
      });
  f("blend_prune_threshold", s.blend_prune_threshold, OmitIf{TrainOptions().blend_prune_threshold});
  f.custom(
      "schedule", [&] { return Json(to_string(s.schedule)); },
      [&](const JsonReader& r, const std::string& k) {
        if (r.has(k)) s.schedule = parse_schedule(r.get<std::string>(k), r.where(k));
      });
  f("min_opacity", s.min_opacity);
  f("max_screen_size_px", s.max_screen_size_px);
  f("max_world_size", s.max_world_size);
  // A run or checkpoint stored without this key started the prune after the first reset, so it resumes
  // with the start it had (a checkpoint stores the effective, scaled options).
  f("large_prune_from", s.large_prune_from, WhenAbsent{s.opacity_reset_interval});
  // Runs and checkpoints stored without this key trained with the reference rule, and a resumed one
  // must go on with it, not switch silently.
  f("large_prune", s.large_prune, OneOf{LargePrune::kCameraExtent, LargePrune::kDistance},
    WhenAbsent{LargePrune::kCameraExtent});
  f("max_gaussians", s.max_gaussians);
  f("downsample_start", s.downsample_start);
  f("full_resolution_at", s.full_resolution_at);
  f("background", s.background);
  f("random_init", s.random_init, OneOf{RandomInit::kFrustum, RandomInit::kPhotoConsistent});
  f("random_init_count", s.random_init_count);
  f("distractors_per_view", s.distractors_per_view);
  f("distractor_opacity_weight", s.distractor_opacity_weight);
  f("in_the_wild", s.in_the_wild);
  f("in_the_wild_from", s.in_the_wild_from);
  f("visibility_weight", s.visibility_weight);
  f("robust", s.robust, OneOf{Robust::kNone, Robust::kRobustFilter});
  f("mask_normalization", s.mask_normalization, OneOf{MaskNormalization::kValid, MaskNormalization::kReference});
  f("random_init_near_m", s.random_init_near_m);
  f("random_init_far_m", s.random_init_far_m);
};

}  // namespace

Json TrainOptions::to_json() const { return json_fields::write(*this, kFields); }

const char* to_string(TrainOptions::RandomInit r) {
  return r == TrainOptions::RandomInit::kFrustum ? "frustum" : "photo";
}

const char* to_string(TrainOptions::Robust r) {
  return r == TrainOptions::Robust::kRobustFilter ? "robust_filter" : "none";
}

const char* to_string(TrainOptions::LargePrune p) {
  return p == TrainOptions::LargePrune::kCameraExtent ? "camera_extent" : "distance";
}

TrainOptions::LargePrune parse_large_prune(const std::string& s, const std::string& where) {
  for (TrainOptions::LargePrune p : {TrainOptions::LargePrune::kCameraExtent, TrainOptions::LargePrune::kDistance})
    if (s == to_string(p)) return p;
  throw InputError(where, "expected distance or camera_extent, got '" + s + "'");
}

const char* to_string(TrainOptions::Schedule s) {
  switch (s) {
    case TrainOptions::Schedule::kFast: return "fast";
    case TrainOptions::Schedule::kReference: return "reference";
    case TrainOptions::Schedule::kUnscaled: return "unscaled";
  }
  return "?";
}

TrainOptions::Schedule parse_schedule(const std::string& s, const std::string& where) {
  using S = TrainOptions::Schedule;
  for (S v : {S::kFast, S::kReference, S::kUnscaled})
    if (s == to_string(v)) return v;
  // Records written before the fast schedule called the reference's scaled form "scaled".
  if (s == "scaled") return S::kReference;
  throw InputError(where, "expected fast, reference or unscaled, got '" + s + "'");
}

TrainOptions TrainOptions::with_run_length(int views, int64_t pixels) const {
  WGS_CHECK(views > 0 && pixels > 0);
  constexpr int kReferenceIterations = 30000, kRound = 100;
  TrainOptions o = *this;
  if (iterations == 0) {
    if (schedule == Schedule::kFast) {
      const int passes = (kFastEpochs * views + kRound - 1) / kRound * kRound;
      o.iterations = std::clamp(passes, kFastMinIterations, kReferenceIterations);
    } else {
      o.iterations = kReferenceIterations;
    }
  }
  if (schedule == Schedule::kFast && max_gaussians == TrainOptions().max_gaussians)
    o.max_gaussians = std::min(max_gaussians, int64_t(std::llround(kFastGaussiansPerPixel * double(pixels))));
  return o;
}

TrainOptions TrainOptions::with_run_length(const std::vector<Camera>& train_cameras) const {
  int64_t pixels = 0;
  for (const Camera& c : train_cameras) pixels = std::max(pixels, int64_t(c.width) * c.height);
  return with_run_length(int(train_cameras.size()), pixels);
}

TrainOptions TrainOptions::effective() const {
  constexpr int kReferenceIterations = 30000;
  constexpr int kResetsPerDensification = 30;  // reference: reset every 3000, densify every 100
  TrainOptions e = *this;
  WGS_CHECK(iterations > 0);  // with_run_length() resolves 0 before training
  const TrainOptions ref;
  // Robust runs never reset opacity (the reference's robust loss skips it), unless set by hand.
  if (robust != Robust::kNone && opacity_reset_interval == ref.opacity_reset_interval)
    e.opacity_reset_interval = std::numeric_limits<int>::max();
  if (schedule == Schedule::kUnscaled || iterations >= kReferenceIterations) return e;
  const double s = double(iterations) / kReferenceIterations;
  // Only fields still at the reference's value are scaled: a value set by hand is taken as given.
  auto scaled = [&](int v, int reference, int floor) {
    return v == reference ? std::max(floor, int(std::lround(v * s))) : v;
  };
  e.densify_from = scaled(densify_from, ref.densify_from, 0);
  e.densify_until = scaled(densify_until, ref.densify_until, 1);
  e.large_prune_from = scaled(large_prune_from, ref.large_prune_from, 0);
  // densification_interval is not scaled below the reference's 100 iterations: that is the time a
  // split or cloned Gaussian gets to settle before it is judged again, whatever the run length.
  // Scaled (to 10 at 2000 iterations), copies that had not settled were split again at the next
  // step; on heavy rain (pool_rain quick, 186 points) that compounded to 589k Gaussians by iteration
  // 1000. Only runs too short for kMinDensificationSteps steps at 100 densify more often, so that
  // every run can still grow from a sparse SfM cloud (docs/reconstruction.md).
  constexpr int kMinDensificationSteps = 8;
  if (densification_interval == ref.densification_interval) {
    const int window = std::max(1, e.densify_until - e.densify_from);
    e.densification_interval = std::max(1, std::min(densification_interval, window / kMinDensificationSteps));
  }
  // At least 30 densification steps between two resets, as in the reference (3000 / 100): a plain
  // scaling reset every few densifications, the opacities never recovered and pruning emptied the
  // model.
  if (robust == Robust::kNone)
    e.opacity_reset_interval = scaled(opacity_reset_interval, ref.opacity_reset_interval,
                                      kResetsPerDensification * e.densification_interval);
  e.sh_degree_interval = scaled(sh_degree_interval, ref.sh_degree_interval, 1);
  return e;
}

TrainOptions TrainOptions::from_json(const JsonReader& r) {
  TrainOptions o = json_fields::read(r, TrainOptions{}, kFields, json_fields::Absent::kKeep);
  o.validate(r.where());
  return o;
}

TrainOptions TrainOptions::from_user_json(const JsonReader& r) {
  TrainOptions o = json_fields::read(r, TrainOptions{}, kFields, json_fields::Absent::kDefaults);
  o.validate(r.where());
  return o;
}

}  // namespace weathergs::reconstruction
