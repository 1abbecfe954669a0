// A 3000-iteration run end to end (train_run, render_run) with the reference schedule scaled to it
// and with its counts unscaled: the unscaled one ends on an opacity reset. Slow (~40-75 s on 2 cores): label slow; the
// schedule arithmetic itself is tested in schedule_test.cc.
#include <gtest/gtest.h>

#include <algorithm>

#include "core/dataset.h"
#include "core/image.h"
#include "reconstruction/run.h"
#include "tests/core/test_util.h"
#include "tests/reconstruction/test_scene.h"

namespace weathergs::reconstruction {
namespace {

// A short run through train_run/render_run: with the scaled schedule the final model renders the
// held-out views well; with the reference schedule the same run ends on a reset.
TEST(Schedule, ShortRunDoesNotEndOnAReset) {
  weathergs::testing::TempDir dir;
  const GaussianSet<float> truth = testing::random_gaussians<float>(100, 5, 1.0, 0.15, 0.0);
  const Dataset d =
      testing::write_synthetic_dataset(dir / "data", truth, testing::ring_cameras(9, 32, 24, 30, 4.0), true);
  auto test_psnr = [&](TrainOptions::Schedule schedule, const std::string& name) {
    TrainRunOptions o;
    o.dataset = d.root;
    o.out = dir / name;
    o.train.iterations = 3000;
    o.checkpoint_every = 0;
    o.train.schedule = schedule;
    o.train.seed = 1;
    train_run(o);
    RenderRunOptions r;
    r.model = o.out;
    r.out = dir / (name + "_renders");
    render_run(r);
    return testing::mean_test_psnr(d, r.out);
  };
  // 3000 iterations, the README's example: the reference schedule resets opacity at iteration 3000,
  // the last one. Bars: the scaled run must be a sensible reconstruction (25 dB) and far better than
  // the reset one (10 dB).
  const double scaled = test_psnr(TrainOptions::Schedule::kReference, "scaled");
  const double reference = test_psnr(TrainOptions::Schedule::kUnscaled, "reference");
  std::printf("3000-iteration run, test PSNR: scaled schedule %.2f dB, reference schedule %.2f dB\n", scaled,
              reference);
  EXPECT_GT(scaled, 25.0);
  EXPECT_GT(scaled, reference + 10.0);
}

}  // namespace
}  // namespace weathergs::reconstruction
