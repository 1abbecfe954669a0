// The compressed schedule's pieces in the trainer: the blend-weight prune (exactly the Gaussians no
// pixel blends above the threshold; thread independence; resume across it) and the held position
// learning rate.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/atomic_file.h"
#include "core/parallel.h"
#include "reconstruction/trainer.h"
#include "tests/core/test_util.h"
#include "tests/reconstruction/test_scene.h"

namespace weathergs::reconstruction {
namespace {

using testing::look_at_camera;
using testing::random_gaussians;
using testing::ring_cameras;

std::vector<TrainView> views_of(const GaussianSet<float>& truth, const std::vector<Camera>& cameras) {
  std::vector<TrainView> views;
  for (const Camera& cam : cameras) {
    RasterState<float> st;
    rasterize_forward(truth, RasterCamera<float>::from(cam), RasterSettings<float>{}, &st);
    TrainView v;
    v.camera = cam;
    v.rgb = st.image;
    for (float& x : v.rgb) x = std::clamp(x, 0.f, 1.f);
    views.push_back(std::move(v));
  }
  return views;
}

std::vector<Camera> cameras_of(const std::vector<TrainView>& views) {
  std::vector<Camera> c;
  for (const TrainView& v : views) c.push_back(v.camera);
  return c;
}

// One isotropic Gaussian row: centre, scale (m), opacity, grey level.
void set_gaussian(GaussianSet<float>* g, size_t i, const Eigen::Vector3d& p, double scale, double opacity, double grey) {
  for (int k = 0; k < 3; ++k) {
    g->position[i * 3 + k] = float(p[k]);
    g->log_scale[i * 3 + k] = float(std::log(scale));
  }
  g->rotation[i * 4] = 1.f;
  g->opacity_logit[i] = float(inverse_sigmoid(opacity));
  for (int c = 0; c < 3; ++c) g->sh[i * kShFloats + c] = float(rgb_to_sh0(grey));
}

// A hand-made scene seen by two cameras from -y: an opaque wall, one Gaussian hidden behind it, a
// faint one, a visible one, a half-transparent one and one behind the cameras. With the threshold
// at 0.05 the prune must remove the hidden, the faint and the unseen one, and nothing else: exactly
// the Gaussians whose largest weight over every pixel of both views (the per-pixel loop in double,
// test_scene.h) is below it.
TEST(BlendPruneTest, RemovesExactlyTheGaussiansNoPixelBlendsAboveTheThreshold) {
  constexpr double kThreshold = 0.05;
  GaussianSet<float> g;
  g.assign_zero(6);
  set_gaussian(&g, 0, {0, 0, 0}, 0.6, 0.999, 0.5);    // the wall
  set_gaussian(&g, 1, {0, 0.8, 0}, 0.08, 0.9, 0.9);   // behind the wall
  set_gaussian(&g, 2, {1.2, 0, 0}, 0.2, 0.03, 0.9);   // faint
  set_gaussian(&g, 3, {-1.2, 0, 0}, 0.2, 0.8, 0.2);   // visible
  set_gaussian(&g, 4, {0, -10, 0}, 0.2, 0.9, 0.9);    // behind the cameras
  set_gaussian(&g, 5, {0, 0, 1.1}, 0.15, 0.2, 0.8);   // half-transparent, in the open
  const std::vector<Camera> cams = {look_at_camera("a", 48, 36, 40, {-0.3, -5, 0.1}),
                                    look_at_camera("b", 48, 36, 40, {0.3, -5, -0.1})};
  std::vector<double> best(g.size(), 0.0);
  for (const Camera& c : cams) {
    const std::vector<double> w = testing::reference_max_blend_weights(g.cast<double>(), c);
    for (size_t i = 0; i < g.size(); ++i) best[i] = std::max(best[i], w[i]);
  }
  for (size_t i = 0; i < g.size(); ++i) {
    std::printf("Gaussian %zu: largest blend weight %.4f\n", i, best[i]);
    // Far from the threshold, so that float rounding cannot decide the case.
    ASSERT_GT(std::abs(best[i] - kThreshold), 0.3 * kThreshold) << "Gaussian " << i;
  }
  const std::vector<char> expect_kept = {1, 0, 0, 1, 0, 1};  // what the scene was made to show
  for (size_t i = 0; i < g.size(); ++i) ASSERT_EQ(best[i] >= kThreshold, bool(expect_kept[i])) << "Gaussian " << i;

  TrainOptions o;
  o.schedule = TrainOptions::Schedule::kUnscaled;
  o.iterations = 10;
  o.densify_from = 100;  // no densification: the step below only trains
  Trainer t(views_of(g, cams), g, o, scene_extent(cams));
  EXPECT_EQ(t.prune_by_blend_weight(kThreshold), 3);
  GaussianSet<float> kept = g;
  kept.keep(expect_kept);
  EXPECT_EQ(t.gaussians().position, kept.position);
  EXPECT_EQ(t.gaussians().opacity_logit, kept.opacity_logit);
  EXPECT_EQ(t.gaussians().sh, kept.sh);
  EXPECT_EQ(t.owners().size(), 3u);
  t.step();  // the statistics and Adam moments were cut to the same rows
  EXPECT_EQ(t.gaussians().size(), 3u);
}

// Densification every 10 iterations up to 30, no opacity reset, the blend-weight prune at 30.
TrainOptions prune_options() {
  TrainOptions o;
  o.schedule = TrainOptions::Schedule::kUnscaled;
  o.iterations = 40;
  o.densify_from = 5;
  o.densify_until = 30;
  o.densification_interval = 10;
  o.opacity_reset_interval = 1000;
  o.sh_degree_interval = 10;
  o.densify_grad_threshold = 2e-5;
  o.blend_prune_at = {30};
  o.blend_prune_threshold = 0.12;  // the initial opacity 0.1 has grown to ~0.2 at most by then
  o.position_lr_hold_until = 30;
  return o;
}

struct Scene {
  GaussianSet<float> init;
  std::vector<TrainView> views;
};

Scene make_scene() {
  Scene s;
  const GaussianSet<float> truth = random_gaussians<float>(150, 3, 1.0, 0.1, 0.0);
  s.views = views_of(truth, ring_cameras(4, 64, 48, 64 * 0.9, 4.0));
  s.init = random_gaussians<float>(150, 4, 1.0, 0.1, 0.0);
  for (float& x : s.init.opacity_logit) x = float(inverse_sigmoid(0.1));
  return s;
}

// With 1 and 2 threads the same model, and the prune at 30 removed Gaussians; a run resumed from a
// checkpoint written before the prune (at 23) ends with the uninterrupted run's model.
TEST(BlendPruneTest, SameBitsWithOneOrTwoThreadsAndResumesAcrossThePrune) {
  const Scene s = make_scene();
  const TrainOptions o = prune_options();
  const double extent = scene_extent(cameras_of(s.views));
  weathergs::testing::TempDir dir;
  int64_t before = 0, after = 0;
  auto run = [&](int threads, int stop_at, const std::string& resume_from) {
    set_num_threads(threads);
    Trainer t(s.views, s.init, o, extent);
    if (!resume_from.empty()) t.load_checkpoint(resume_from);
    while (t.iteration() < stop_at) {
      const IterationStats st = t.step();
      if (st.iteration == 29) before = st.num_gaussians;
      if (st.iteration == 30) after = st.num_gaussians;
    }
    return t;
  };
  const Trainer one = run(1, 40, "");
  std::printf("blend prune at 30: %lld -> %lld Gaussians\n", static_cast<long long>(before),
              static_cast<long long>(after));
  EXPECT_GT(before, 150);        // densification ran
  EXPECT_LT(after, before);      // the prune removed some
  EXPECT_GT(after, before / 4);  // and not the scene
  const Trainer two = run(2, 40, "");
  EXPECT_EQ(one.gaussians().position, two.gaussians().position);
  EXPECT_EQ(one.gaussians().sh, two.gaussians().sh);
  EXPECT_EQ(one.gaussians().opacity_logit, two.gaussians().opacity_logit);
  run(1, 23, "").save_checkpoint(dir / "ckpt.bin", 1.0);
  const Trainer resumed = run(2, 40, dir / "ckpt.bin");
  set_num_threads(0);
  EXPECT_EQ(one.gaussians().position, resumed.gaussians().position);
  EXPECT_EQ(one.gaussians().log_scale, resumed.gaussians().log_scale);
  EXPECT_EQ(one.gaussians().opacity_logit, resumed.gaussians().opacity_logit);
  // The checkpoint names the prune's options: a run without them cannot resume from it.
  TrainOptions other = o;
  other.blend_prune_at = {31};
  Trainer t(s.views, s.init, other, extent);
  try {
    t.load_checkpoint(dir / "ckpt.bin");
    ADD_FAILURE() << "resumed with another prune";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("blend_prune_at: checkpoint [30], now [31]"), std::string::npos) << e.what();
  }
}

// Held at position_lr_init through position_lr_hold_until, then log-linear to position_lr_final at
// the end; 0 keeps the reference's decay from the start.
TEST(BlendPruneTest, PositionLearningRateHeldThenDecays) {
  const Scene s = make_scene();
  const double extent = scene_extent(cameras_of(s.views));
  TrainOptions o;
  o.schedule = TrainOptions::Schedule::kUnscaled;
  o.iterations = 4500;
  const Trainer reference(s.views, s.init, o, extent);
  o.position_lr_hold_until = 1500;
  const Trainer held(s.views, s.init, o, extent);
  const double init = o.position_lr_init * extent, final = o.position_lr_final * extent;
  constexpr double kRelative = 1e-12;  // exp(log) round trips
  EXPECT_NEAR(reference.position_lr(0), init, kRelative * init);
  EXPECT_NEAR(reference.position_lr(2250), std::sqrt(init * final), kRelative * init);
  EXPECT_LT(reference.position_lr(1500), 0.3 * init);
  EXPECT_NEAR(held.position_lr(1), init, kRelative * init);
  EXPECT_NEAR(held.position_lr(1500), init, kRelative * init);
  EXPECT_NEAR(held.position_lr(3000), std::sqrt(init * final), kRelative * init);
  EXPECT_NEAR(held.position_lr(4500), final, kRelative * init);
  EXPECT_LT(held.position_lr(1600), init);
}

TEST(BlendPruneTest, OptionsAreValidatedAndWrittenOnlyWhenSet) {
  const Json plain = TrainOptions{}.to_json();
  EXPECT_FALSE(plain.contains("blend_prune_at"));  // the other schedules' records keep their bytes
  EXPECT_FALSE(plain.contains("blend_prune_threshold"));
  EXPECT_FALSE(plain.contains("position_lr_hold_until"));
  TrainOptions o = prune_options();
  const Json j = o.to_json();
  EXPECT_EQ(j.at("blend_prune_at"), Json({30}));
  EXPECT_EQ(TrainOptions::from_json(JsonReader(j, "x")).to_json(), j);
  EXPECT_EQ(TrainOptions::from_user_json(JsonReader(j, "x")).blend_prune_at, std::vector<int>{30});
  auto rejects = [](TrainOptions bad, const char* field) {
    try {
      bad.validate("x");
      ADD_FAILURE() << field << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  TrainOptions bad = o;
  bad.blend_prune_at = {30, 30};
  rejects(bad, "blend_prune_at[1]");
  bad.blend_prune_at = {0};
  rejects(bad, "blend_prune_at[0]");
  bad = o;
  bad.blend_prune_threshold = 0;
  rejects(bad, "blend_prune_threshold");
  bad = o;
  bad.position_lr_hold_until = -1;
  rejects(bad, "position_lr_hold_until");
  Json wrong = j;
  wrong["blend_prune_at"] = 30;  // not an array
  EXPECT_THROW(TrainOptions::from_user_json(JsonReader(wrong, "x")), InputError);
  wrong["blend_prune_at"] = Json({1.5});
  EXPECT_THROW(TrainOptions::from_user_json(JsonReader(wrong, "x")), InputError);
}

}  // namespace
}  // namespace weathergs::reconstruction
