// TrainOptions: validation, the run-length-scaled schedule (effective()) and the JSON round trip.
// Split from trainer.cc, which keeps the optimisation itself.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.h"
#include "reconstruction/trainer.h"

namespace weathergs::reconstruction {

void TrainOptions::validate(const std::string& where) const {
  auto fail = [&](const std::string& field, const std::string& value, const std::string& rule) {
    throw InputError(where, field + " = " + value + ": " + rule);
  };
  auto positive = [&](const char* name, double v) {
    if (!(v > 0) || !std::isfinite(v)) fail(name, std::to_string(v), "must be a positive finite number");
  };
  if (iterations < 1) fail("iterations", std::to_string(iterations), "must be >= 1");
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
  if (random_init_count < 1) fail("random_init_count", std::to_string(random_init_count), "must be >= 1");
  if (!(random_init_near_m > 0 && random_init_far_m > random_init_near_m && std::isfinite(random_init_far_m)))
    fail("random_init_near_m/far_m", std::to_string(random_init_near_m) + "/" + std::to_string(random_init_far_m),
         "need 0 < near < far < inf");
}

Json TrainOptions::to_json() const {
  return Json{{"iterations", iterations},
              {"seed", seed},
              {"lambda_dssim", lambda_dssim},
              {"position_lr_init", position_lr_init},
              {"position_lr_final", position_lr_final},
              {"feature_lr", feature_lr},
              {"opacity_lr", opacity_lr},
              {"scaling_lr", scaling_lr},
              {"rotation_lr", rotation_lr},
              {"adam_beta1", adam_beta1},
              {"adam_beta2", adam_beta2},
              {"adam_eps", adam_eps},
              {"max_sh_degree", max_sh_degree},
              {"sh_degree_interval", sh_degree_interval},
              {"percent_dense", percent_dense},
              {"densify_from", densify_from},
              {"densify_until", densify_until},
              {"densification_interval", densification_interval},
              {"densify_grad_threshold", densify_grad_threshold},
              {"opacity_reset_interval", opacity_reset_interval},
              {"schedule", to_string(schedule)},
              {"min_opacity", min_opacity},
              {"max_screen_size_px", max_screen_size_px},
              {"max_world_size", max_world_size},
              {"large_prune_from", large_prune_from},
              {"large_prune", to_string(large_prune)},
              {"max_gaussians", max_gaussians},
              {"background", {background[0], background[1], background[2]}},
              {"random_init", to_string(random_init)},
              {"robust", to_string(robust)},
              {"mask_normalization", to_string(mask_normalization)},
              {"distractors_per_view", distractors_per_view},
              {"distractor_opacity_weight", distractor_opacity_weight},
              {"in_the_wild", in_the_wild},
              {"in_the_wild_from", in_the_wild_from},
              {"visibility_weight", visibility_weight},
              {"random_init_count", random_init_count},
              {"random_init_near_m", random_init_near_m},
              {"random_init_far_m", random_init_far_m}};
}

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
  return s == TrainOptions::Schedule::kScaled ? "scaled" : "reference";
}

TrainOptions TrainOptions::effective() const {
  constexpr int kReferenceIterations = 30000;
  constexpr int kResetsPerDensification = 30;  // reference: reset every 3000, densify every 100
  TrainOptions e = *this;
  const TrainOptions ref;
  // Robust runs never reset opacity (the reference's robust loss skips it), unless set by hand.
  if (robust != Robust::kNone && opacity_reset_interval == ref.opacity_reset_interval)
    e.opacity_reset_interval = std::numeric_limits<int>::max();
  if (schedule != Schedule::kScaled || iterations >= kReferenceIterations) return e;
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
  TrainOptions o;
  o.iterations = r.get_or("iterations", o.iterations);
  o.seed = r.get_or<uint64_t>("seed", o.seed);
  o.lambda_dssim = r.get_or("lambda_dssim", o.lambda_dssim);
  o.position_lr_init = r.get_or("position_lr_init", o.position_lr_init);
  o.position_lr_final = r.get_or("position_lr_final", o.position_lr_final);
  o.feature_lr = r.get_or("feature_lr", o.feature_lr);
  o.opacity_lr = r.get_or("opacity_lr", o.opacity_lr);
  o.scaling_lr = r.get_or("scaling_lr", o.scaling_lr);
  o.rotation_lr = r.get_or("rotation_lr", o.rotation_lr);
  o.adam_beta1 = r.get_or("adam_beta1", o.adam_beta1);
  o.adam_beta2 = r.get_or("adam_beta2", o.adam_beta2);
  o.adam_eps = r.get_or("adam_eps", o.adam_eps);
  o.max_sh_degree = r.get_or("max_sh_degree", o.max_sh_degree);
  o.sh_degree_interval = r.get_or("sh_degree_interval", o.sh_degree_interval);
  o.percent_dense = r.get_or("percent_dense", o.percent_dense);
  o.densify_from = r.get_or("densify_from", o.densify_from);
  o.densify_until = r.get_or("densify_until", o.densify_until);
  o.densification_interval = r.get_or("densification_interval", o.densification_interval);
  o.densify_grad_threshold = r.get_or("densify_grad_threshold", o.densify_grad_threshold);
  o.opacity_reset_interval = r.get_or("opacity_reset_interval", o.opacity_reset_interval);
  o.schedule = r.get_enum_or("schedule", o.schedule, {Schedule::kReference, Schedule::kScaled});
  o.min_opacity = r.get_or("min_opacity", o.min_opacity);
  o.max_screen_size_px = r.get_or("max_screen_size_px", o.max_screen_size_px);
  o.max_world_size = r.get_or("max_world_size", o.max_world_size);
  // A run or checkpoint stored without this key started the prune after the first reset, so it resumes
  // with the start it had (a checkpoint stores the effective, scaled options).
  o.large_prune_from = r.get_or("large_prune_from", o.opacity_reset_interval);
  // Runs and checkpoints stored without this key trained with the reference rule, and a resumed one
  // must go on with it, not switch silently.
  o.large_prune = r.get_enum_or("large_prune", LargePrune::kCameraExtent,
                                {LargePrune::kCameraExtent, LargePrune::kDistance});
  o.max_gaussians = r.get_or<int64_t>("max_gaussians", o.max_gaussians);
  if (r.has("background")) {
    JsonReader b = r.child("background");
    if (!b.is_array() || b.size() != 3) throw InputError(b.where(), "expected an array of 3 numbers");
    for (int c = 0; c < 3; ++c) o.background[c] = b.at(c).as<double>();
  }
  o.random_init = r.get_enum_or("random_init", o.random_init,
                                 {RandomInit::kFrustum, RandomInit::kPhotoConsistent});
  o.random_init_count = r.get_or("random_init_count", o.random_init_count);
  o.distractors_per_view = r.get_or("distractors_per_view", o.distractors_per_view);
  o.distractor_opacity_weight = r.get_or("distractor_opacity_weight", o.distractor_opacity_weight);
  o.in_the_wild = r.get_or("in_the_wild", o.in_the_wild);
  o.in_the_wild_from = r.get_or("in_the_wild_from", o.in_the_wild_from);
  o.visibility_weight = r.get_or("visibility_weight", o.visibility_weight);
  o.robust = r.get_enum_or("robust", o.robust, {Robust::kNone, Robust::kRobustFilter});
  o.mask_normalization = r.get_enum_or("mask_normalization", o.mask_normalization,
                                       {MaskNormalization::kValid, MaskNormalization::kReference});
  o.random_init_near_m = r.get_or("random_init_near_m", o.random_init_near_m);
  o.random_init_far_m = r.get_or("random_init_far_m", o.random_init_far_m);
  r.finish();
  o.validate(r.where());
  return o;
}

}  // namespace weathergs::reconstruction
