// The 3DGS trainer's numerics golden (reconstruction/numerics.h): small fixed training runs, one per
// path the methods take (a masked loss with clone, split, prune, opacity reset and the SH schedule;
// the fast schedule's scaled counts; robust-3dgs's mask; desplat's distractors; gs-w-lite's
// appearance and visibility; the random initialization), end in parameters whose sha256 must equal
// tests/data/numerics_golden.json's under the current kTrainerNumericsVersion. The same hashes with
// 1 and 2 threads. ~5 s.
#include <gtest/gtest.h>

#include <map>

#include "core/parallel.h"
#include "reconstruction/init_random.h"
#include "reconstruction/numerics.h"
#include "reconstruction/trainer.h"
#include "tests/core/numerics_golden.h"
#include "tests/reconstruction/test_scene.h"

namespace weathergs::reconstruction {
namespace {

// Four views of 150 random Gaussians on a ring, a square of the first one masked.
std::vector<TrainView> views() {
  const GaussianSet<float> truth = testing::random_gaussians<float>(150, 3, 1.0, 0.1, 0.0);
  std::vector<TrainView> out;
  for (const Camera& cam : testing::ring_cameras(4, 64, 48, 64 * 0.9, 4.0)) {
    RasterState<float> st;
    rasterize_forward(truth, RasterCamera<float>::from(cam), RasterSettings<float>{}, &st);
    TrainView v;
    v.camera = cam;
    v.rgb = st.image;
    for (float& x : v.rgb) x = std::clamp(x, 0.f, 1.f);
    out.push_back(std::move(v));
  }
  out[0].invalid.assign(size_t(64) * 48, 0);
  for (int y = 10; y < 22; ++y)
    for (int x = 20; x < 36; ++x) out[0].invalid[size_t(y) * 64 + x] = 1;
  return out;
}

// A COLMAP-like start: the truth's centres, jittered, grey.
GaussianSet<float> points() {
  const GaussianSet<float> truth = testing::random_gaussians<float>(150, 3, 1.0, 0.1, 0.0);
  std::vector<Eigen::Vector3d> p, c;
  for (size_t i = 0; i < truth.size(); ++i) {
    Rng rng(5, 9, i);
    p.emplace_back(truth.position[i * 3] + 0.02 * rng.normal(), truth.position[i * 3 + 1] + 0.02 * rng.normal(),
                   truth.position[i * 3 + 2] + 0.02 * rng.normal());
    c.emplace_back(0.5, 0.5, 0.5);
  }
  return init_from_points(p, c);
}

// Densification every 10 iterations, a reset every 25 and the SH degree up every 10: every step of
// the optimisation runs within 80 iterations.
TrainOptions busy() {
  TrainOptions o;
  o.iterations = 80;
  o.schedule = TrainOptions::Schedule::kUnscaled;
  o.densify_from = 5;
  o.densify_until = 80;
  o.densification_interval = 10;
  o.opacity_reset_interval = 25;
  o.sh_degree_interval = 10;
  o.densify_grad_threshold = 2e-5;
  o.large_prune_from = 20;
  return o;
}

std::map<std::string, TrainOptions> cases() {
  std::map<std::string, TrainOptions> c;
  c["masked"] = busy();
  TrainOptions fast;
  fast.iterations = 150;  // the fast schedule's counts scaled to 150 iterations
  c["fast"] = fast;
  c["robust"] = busy();
  c["robust"].robust = TrainOptions::Robust::kRobustFilter;
  c["desplat"] = busy();
  c["desplat"].distractors_per_view = 16;
  c["wild"] = busy();
  c["wild"].in_the_wild = true;
  c["wild"].in_the_wild_from = 20;
  c["random_init"] = busy();
  c["random_init"].iterations = 30;
  c["random_init"].random_init_count = 400;
  return c;
}

std::string train_and_hash(const std::string& name, const TrainOptions& o, const std::vector<TrainView>& v) {
  std::vector<Camera> cameras;
  for (const TrainView& view : v) cameras.push_back(view.camera);
  Trainer t(v, name == "random_init" ? init_random(v, o) : points(), o, scene_extent(cameras));
  while (t.iteration() < o.iterations) t.step();
  const GaussianSet<float>& g = t.gaussians();
  return weathergs::testing::sha256_of_arrays(g.position, g.log_scale, g.rotation, g.opacity_logit, g.sh, t.owners());
}

TEST(NumericsGolden, TrainedBitsMatchTheGoldenOfThisNumericsVersion) {
  const std::vector<TrainView> v = views();
  std::map<std::string, std::string> hashes;
  for (const auto& [name, o] : cases()) {
    set_num_threads(1);
    const std::string one = train_and_hash(name, o, v);
    set_num_threads(2);
    const std::string two = train_and_hash(name, o, v);
    set_num_threads(0);
    EXPECT_EQ(one, two) << name << ": the trainer gives other bits on 1 and 2 threads";
    hashes[name] = one;
  }
  weathergs::testing::check_numerics_golden("3dgs", kTrainerNumericsVersion, "kTrainerNumericsVersion (reconstruction/numerics.h)",
                                            hashes);
}

}  // namespace
}  // namespace weathergs::reconstruction
