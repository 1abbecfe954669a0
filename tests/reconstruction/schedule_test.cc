// The iteration schedule scales with the run length: a short run never ends on an opacity reset
// (`train --iterations 3000` must not end right after one, which renders nearly black).
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
  o.schedule = TrainOptions::Schedule::kReference;
  EXPECT_EQ(o.effective().to_json(), o.to_json());
  // A value set by hand is kept.
  o.schedule = TrainOptions::Schedule::kScaled;
  o.opacity_reset_interval = 100000;
  EXPECT_EQ(o.effective().opacity_reset_interval, 100000);
  EXPECT_EQ(o.effective().densify_until, 1500);
}

}  // namespace
}  // namespace weathergs::reconstruction
