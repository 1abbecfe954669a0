// The iteration schedules: the reference's scales with the run length, so a short run never ends on
// an opacity reset (`train --iterations 3000` must not end right after one, which renders nearly
// black); the fast one takes its length and Gaussian budget from the training data.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/dataset.h"
#include "core/image.h"
#include "reconstruction/run.h"
#include "tests/core/test_util.h"
#include "tests/reconstruction/test_scene.h"

namespace weathergs::reconstruction {
namespace {

TEST(Schedule, ScaledToTheRunLengthReferenceAt30000) {
  TrainOptions o;
  o.schedule = TrainOptions::Schedule::kReference;
  o.iterations = 3000;
  const TrainOptions e = o.effective();
  EXPECT_EQ(e.densify_from, 50);
  EXPECT_EQ(e.densify_until, 1500);
  // Not scaled: new Gaussians get the reference's 100 iterations to settle before the next step.
  EXPECT_EQ(e.densification_interval, 100);
  EXPECT_EQ(e.opacity_reset_interval, 3000);
  EXPECT_EQ(e.sh_degree_interval, 100);
  EXPECT_EQ(e.large_prune_from, 300);  // the reference's first reset (3000 of 30000), scaled
  // The last reset (the last multiple of the interval below densify_until) leaves > half the run.
  for (int iterations : {200, 700, 3000, 7000, 29999}) {
    o.iterations = iterations;
    const TrainOptions x = o.effective();
    const int last_reset = ((x.densify_until - 1) / x.opacity_reset_interval) * x.opacity_reset_interval;
    EXPECT_LE(last_reset, iterations / 2) << iterations;
  }
  // Short runs: at least 30 densification steps between resets (at 150 iterations a plain scaling
  // reset every 15 iterations and pruning emptied the model), so no reset at all here.
  o.iterations = 150;
  EXPECT_EQ(o.effective().densification_interval, 9);  // (75 - 2) / 8
  EXPECT_EQ(o.effective().opacity_reset_interval, 270);
  EXPECT_GT(o.effective().opacity_reset_interval, o.effective().densify_until);
  // Runs too short for 8 steps at 100 densify 8 times: 700 iterations densify 12..350 every 42.
  o.iterations = 700;
  EXPECT_EQ(o.effective().densification_interval, 42);
  o.iterations = 2000;
  EXPECT_EQ(o.effective().densification_interval, 100);
  o.iterations = 150;
  // A densification interval set by hand is kept and sets the reset floor.
  o.densification_interval = 10;
  EXPECT_EQ(o.effective().densification_interval, 10);
  EXPECT_EQ(o.effective().opacity_reset_interval, 300);
  o.densification_interval = TrainOptions().densification_interval;
  o.iterations = 30000;
  EXPECT_EQ(o.effective().to_json(), o.to_json());
  o.iterations = 3000;
  o.schedule = TrainOptions::Schedule::kUnscaled;
  EXPECT_EQ(o.effective().to_json(), o.to_json());
  // A value set by hand is kept.
  o.schedule = TrainOptions::Schedule::kReference;
  o.opacity_reset_interval = 100000;
  EXPECT_EQ(o.effective().opacity_reset_interval, 100000);
  EXPECT_EQ(o.effective().densify_until, 1500);
}

// --schedule reference at 30000 iterations is the protocol (graphdeco-inria gaussian-splatting:
// arguments/__init__.py OptimizationParams, and train.py's SH step every 1000 iterations and
// large-Gaussian prune from the first opacity reset), transcribed here independently of
// TrainOptions' defaults: its effective counts are the protocol's, and it trains bit for bit as the
// trainer given those counts by hand under `unscaled` (over a densification step and the first SH
// step). Only the memory guard (max_gaussians) is ours.
TEST(Schedule, ReferenceIsTheProtocolsTrainerBitForBit) {
  TrainOptions hand;
  hand.schedule = TrainOptions::Schedule::kUnscaled;
  hand.iterations = 30000;
  hand.position_lr_init = 0.00016;
  hand.position_lr_final = 0.0000016;
  hand.feature_lr = 0.0025;
  hand.opacity_lr = 0.025;
  hand.scaling_lr = 0.005;
  hand.rotation_lr = 0.001;
  hand.percent_dense = 0.01;
  hand.lambda_dssim = 0.2;
  hand.densification_interval = 100;
  hand.opacity_reset_interval = 3000;
  hand.densify_from = 500;
  hand.densify_until = 15000;
  hand.densify_grad_threshold = 0.0002;
  hand.max_sh_degree = 3;
  hand.sh_degree_interval = 1000;
  hand.min_opacity = 0.005;
  hand.max_world_size = 0.1;
  hand.large_prune_from = 3000;
  TrainOptions reference;
  reference.schedule = TrainOptions::Schedule::kReference;
  reference = reference.with_run_length(14, 300 * 200);
  Json want = hand.effective().to_json(), got = reference.effective().to_json();
  want.erase("schedule");
  got.erase("schedule");
  EXPECT_EQ(got.dump(), want.dump());
  EXPECT_EQ(reference.max_gaussians, TrainOptions().max_gaussians);  // no budget: the memory guard only

  std::vector<TrainView> views;
  const GaussianSet<float> truth = testing::random_gaussians<float>(60, 8, 1.0, 0.15, 0.0);
  for (const Camera& cam : testing::ring_cameras(4, 32, 24, 29.0, 4.0)) {
    TrainView v;
    v.camera = cam;
    v.rgb = testing::render_image(truth, cam).data;
    views.push_back(std::move(v));
  }
  std::vector<Camera> cams;
  for (const TrainView& v : views) cams.push_back(v.camera);
  const GaussianSet<float> init = testing::random_gaussians<float>(40, 9, 1.0, 0.1, 0.0);
  Trainer a(views, init, reference, scene_extent(cams)), b(views, init, hand, scene_extent(cams));
  bool densified = false;
  for (int i = 1; i <= 1100; ++i) {
    const IterationStats sa = a.step(), sb = b.step();
    ASSERT_EQ(sa.loss, sb.loss) << "iteration " << i;
    ASSERT_EQ(sa.densified, sb.densified) << "iteration " << i;
    densified |= sa.densified;
  }
  EXPECT_TRUE(densified);
  EXPECT_EQ(a.sh_degree(), 1);
  EXPECT_EQ(a.sh_degree(), b.sh_degree());
  EXPECT_EQ(a.gaussians().position, b.gaussians().position);
  EXPECT_EQ(a.gaussians().sh, b.gaussians().sh);
  EXPECT_EQ(a.gaussians().opacity_logit, b.gaussians().opacity_logit);
  EXPECT_EQ(a.gaussians().log_scale, b.gaussians().log_scale);
  EXPECT_EQ(a.gaussians().rotation, b.gaussians().rotation);
}

// The fast schedule (the default): the reference's form scaled to a length from the number of
// training views, with a Gaussian budget from the image size. --iterations overrides the length.
TEST(Schedule, FastLengthAndBudgetComeFromTheTrainingData) {
  using S = TrainOptions::Schedule;
  TrainOptions o;
  ASSERT_EQ(o.schedule, S::kFast);
  ASSERT_EQ(o.iterations, 0);
  const int64_t quick = 300 * 200, paper = 600 * 400;
  // 500 passes over the views, rounded up to 100, within [3000, 30000].
  EXPECT_EQ(o.with_run_length(14, quick).iterations, 7000);    // quick profile: 14 of 16 views train
  EXPECT_EQ(o.with_run_length(29, paper).iterations, 14500);   // paper profile: 29 of 34
  EXPECT_EQ(o.with_run_length(3, quick).iterations, 3000);
  EXPECT_EQ(o.with_run_length(15, quick).iterations, 7500);
  EXPECT_EQ(o.with_run_length(200, paper).iterations, 30000);
  // The budget: 2 Gaussians per pixel of the largest training image, under the memory guard.
  EXPECT_EQ(o.with_run_length(14, quick).max_gaussians, 120000);
  EXPECT_EQ(o.with_run_length(29, paper).max_gaussians, 480000);
  EXPECT_EQ(o.with_run_length(29, int64_t(4000) * 3000).max_gaussians, TrainOptions().max_gaussians);
  // Explicit values are kept; a resolved set resolves to itself.
  TrainOptions given = o;
  given.iterations = 1234;
  given.max_gaussians = 5000;
  EXPECT_EQ(given.with_run_length(14, quick).to_json(), given.to_json());
  const TrainOptions r = o.with_run_length(14, quick);
  EXPECT_EQ(r.with_run_length(14, quick).to_json(), r.to_json());
  // The others take the reference's 30000 and no budget.
  for (S s : {S::kReference, S::kUnscaled}) {
    TrainOptions x;
    x.schedule = s;
    EXPECT_EQ(x.with_run_length(14, quick).iterations, 30000);
    EXPECT_EQ(x.with_run_length(14, quick).max_gaussians, TrainOptions().max_gaussians);
  }
  // At any length fast densifies as the reference scaled to it, and never ends on a reset: its
  // last reset leaves at least half the run to recover.
  for (int views : {3, 9, 14, 34, 60}) {
    TrainOptions f = o.with_run_length(views, quick), ref = f;
    ref.schedule = S::kReference;
    ref.max_gaussians = f.max_gaussians;
    EXPECT_EQ(f.effective().to_json().dump(), [&] {
      Json j = ref.effective().to_json();
      j["schedule"] = "fast";
      return j.dump();
    }()) << views;
    const TrainOptions e = f.effective();
    const int last_reset = ((e.densify_until - 1) / e.opacity_reset_interval) * e.opacity_reset_interval;
    EXPECT_LE(last_reset, f.iterations / 2) << views;
  }
  // Names, and the name reference had before fast existed.
  EXPECT_EQ(parse_schedule("fast", "x"), S::kFast);
  EXPECT_EQ(parse_schedule("scaled", "x"), S::kReference);
  EXPECT_EQ(parse_schedule("unscaled", "x"), S::kUnscaled);
  EXPECT_THROW(parse_schedule("quick", "--schedule"), InputError);
  Json old = TrainOptions().to_json();
  old["schedule"] = "scaled";
  EXPECT_EQ(TrainOptions::from_json(JsonReader(old, "x")).schedule, S::kReference);
}

}  // namespace
}  // namespace weathergs::reconstruction
