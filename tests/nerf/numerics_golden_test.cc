// The radiance-field trainer's numerics golden (nerf/numerics.h): a small fixed run on the toy plane
// (a masked view, the coarse-to-fine upsample, total variation, the environment) ends in a field
// whose sha256 must equal tests/data/numerics_golden.json's under the current
// kFieldNumericsVersion. The same hash with 1 and 2 threads. ~3 s.
#include <gtest/gtest.h>

#include <map>

#include "core/parallel.h"
#include "nerf/numerics.h"
#include "nerf/trainer.h"
#include "tests/core/numerics_golden.h"
#include "tests/nerf/test_scene.h"

namespace weathergs::nerf {
namespace {

std::string train_and_hash(const std::vector<TrainView>& views, const NerfOptions& o) {
  NerfTrainer t(views, forward_facing_frame(testing::cams(views), 1.5), o);
  while (t.iteration() < o.iterations) t.step();
  return weathergs::testing::sha256_of_arrays(t.field().params(), t.field().env());
}

TEST(NumericsGolden, TrainedFieldMatchesTheGoldenOfThisNumericsVersion) {
  std::vector<TrainView> views = testing::plane_views();
  views[1].invalid.assign(views[1].rgb.size() / 3, 0);
  for (size_t p = 0; p < views[1].invalid.size(); p += 5) views[1].invalid[p] = 1;
  NerfOptions o;
  o.iterations = 45;
  o.batch_rays = 512;
  o.seed = 4;
  o.depth_cells = 24;
  o.level_scales = {0.5, 1.0};
  o.upsample_at = {15};
  o.tv_fraction = 0.1;
  std::map<std::string, std::string> hashes;
  set_num_threads(1);
  hashes["plane"] = train_and_hash(views, o);
  set_num_threads(2);
  EXPECT_EQ(train_and_hash(views, o), hashes["plane"]) << "the field differs between 1 and 2 threads";
  set_num_threads(0);
  weathergs::testing::check_numerics_golden("nerf", kFieldNumericsVersion, "kFieldNumericsVersion (nerf/numerics.h)",
                                            hashes);
}

}  // namespace
}  // namespace weathergs::nerf
