// The classical particle filter (restoration/aef/particle_filter.h) and `weathergs filter`.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/json_reader.h"
#include "core/rng.h"
#include "restoration/aef/filter_dataset.h"
#include "tests/core/test_util.h"
#include "tests/restoration/restoration_test_util.h"
#include "tests/generator/test_scene.h"

namespace weathergs::restoration::aef {
namespace {

namespace fs = std::filesystem;

// A smooth scene (features much wider than a particle) and, over it, bright particles: discs of
// radius 1-2 px (snow) and 1 px wide streaks 6-12 px long (rain), alpha-composited.
struct Synthetic {
  Image background, weathered, alpha;
};

Synthetic make_synthetic(int w, int h, int particles, uint64_t seed) {
  Synthetic s;
  s.background = Image(w, h, 3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double u = double(x) / w, v = double(y) / h;
      s.background.at(x, y, 0) = float(0.3 + 0.2 * std::sin(6 * u) * std::cos(4 * v));
      s.background.at(x, y, 1) = float(0.35 + 0.25 * v);
      s.background.at(x, y, 2) = float(0.4 + 0.15 * std::cos(5 * u + 2 * v));
    }
  s.alpha = Image(w, h, 1, ColorSpace::kLinear);
  for (int i = 0; i < particles; ++i) {
    Rng rng(seed, 1, uint64_t(i));
    const double cx = rng.uniform(0, w), cy = rng.uniform(0, h);
    const bool streak = i % 2 == 1;
    const double r = rng.uniform(1.0, 2.0), len = rng.uniform(6, 12), opacity = rng.uniform(0.5, 0.9);
    for (int y = std::max(0, int(cy - 8)); y < std::min(h, int(cy + 9)); ++y)
      for (int x = std::max(0, int(cx - 4)); x < std::min(w, int(cx + 5)); ++x) {
        const double dx = x + 0.5 - cx, dy = y + 0.5 - cy;
        const bool in = streak ? (std::abs(dx + 0.2 * dy) < 0.6 && std::abs(dy) < len / 2) : (dx * dx + dy * dy < r * r);
        if (in) s.alpha.at(x, y) = std::max(s.alpha.at(x, y), float(opacity));
      }
  }
  s.weathered = s.background;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        const float a = s.alpha.at(x, y);
        s.weathered.at(x, y, c) = (1 - a) * s.background.at(x, y, c) + a * 0.95f;
      }
  return s;
}

double psnr(const Image& a, const Image& b) {
  double mse = 0;
  for (size_t i = 0; i < a.data.size(); ++i) mse += double(a.data[i] - b.data[i]) * (a.data[i] - b.data[i]);
  return 10 * std::log10(1.0 / (mse / a.data.size()));
}

TEST(ParticleFilterTest, RemovesSmallBrightParticlesAndLeavesTheSceneAlone) {
  const Synthetic s = make_synthetic(300, 200, 400, 3);
  const ParticleFilterResult r = filter_particles(s.weathered, {}, "synthetic");
  const double before = psnr(s.weathered, s.background), after = psnr(r.restored, s.background);
  std::printf("PSNR to the particle-free scene: %.2f dB -> %.2f dB, %.1f%% of pixels masked\n", before, after,
              100 * r.mask_fraction);
  EXPECT_GT(after, before + 8.0);
  int particle = 0, found = 0;
  for (size_t p = 0; p < s.alpha.data.size(); ++p)
    if (s.alpha.data[p] > 0.3f) ++particle, found += r.mask.data[p] > 0.5f;
  EXPECT_GT(found, 0.9 * particle);
  // No particles: nothing masked, the image comes back as it was.
  const ParticleFilterResult clear = filter_particles(s.background, {}, "clear");
  EXPECT_EQ(clear.mask_fraction, 0.0);
  EXPECT_EQ(clear.restored.data, s.background.data);
}

TEST(ParticleFilterTest, ExtremeAndBadInputs) {
  // Flat black, flat white, a single bright pixel on black, the smallest image: finite, sensible.
  for (float v : {0.f, 1.f}) {
    const ParticleFilterResult r = filter_particles(Image(16, 12, 3, ColorSpace::kSRGB, v), {}, "flat");
    EXPECT_EQ(r.mask_fraction, 0.0);
    for (float x : r.restored.data) EXPECT_EQ(x, v);
  }
  Image dot(16, 12, 3);
  for (int c = 0; c < 3; ++c) dot.at(8, 6, c) = 1.f;
  const ParticleFilterResult d = filter_particles(dot, {}, "dot");
  EXPECT_EQ(d.mask.at(8, 6), 1.f);
  EXPECT_EQ(d.restored.at(8, 6, 0), 0.f);
  EXPECT_NO_THROW(filter_particles(Image(3, 3, 4), {}, "tiny rgba"));
  EXPECT_THROW(filter_particles(Image(16, 12, 1), {}, "grey"), InputError);
  EXPECT_THROW(filter_particles(Image(2, 12, 3), {}, "narrow"), InputError);
  Image nan(16, 12, 3);
  nan.at(3, 4, 1) = std::nanf("");
  EXPECT_THROW(filter_particles(nan, {}, "nan"), InputError);
  ParticleFilterOptions o;
  o.threshold = 0;
  EXPECT_THROW(filter_particles(dot, o, "x"), InputError);
  o = {};
  o.radius_px_at_300 = -1;
  EXPECT_THROW(o.validate(), InputError);
}

using testing_util::run_cli;

TEST(FilterDatasetTest, EveryViewFilteredWithAReportAndNothingOnBadInput) {
  testing::TempDir tmp;
  testing::SceneOptions so;
  so.views = 4;
  testing::make_clean_dataset(tmp / "d", so);
  ASSERT_EQ(run_cli("filter --method tophat --task always --data " + (tmp / "d") + " --images clean --out " + (tmp / "f"), tmp / "1.log"), 0)
      << read_file(tmp / "1.log");
  const Dataset ds = read_dataset(tmp / "d");
  for (const Camera& c : ds.cameras) {
    const Image img = read_image(tmp / ("f/" + c.name + ".png"));
    EXPECT_EQ(img.width, c.width);
    EXPECT_TRUE(fs::exists(tmp / ("f/masks/" + c.name + ".png")));
  }
  const Json j = read_json_file(tmp / "f/filter.json");
  EXPECT_EQ(j.at("method"), "tophat");
  EXPECT_EQ(j.at("views").size(), ds.cameras.size());
  // The same call again gives byte-identical images (any thread count: views are independent).
  ASSERT_EQ(run_cli("--threads 1 filter --method tophat --task always --data " + (tmp / "d") + " --images clean --mode mask --out " + (tmp / "m1"),
                    tmp / "2.log"), 0);
  ASSERT_EQ(run_cli("--threads 2 filter --method tophat --task always --data " + (tmp / "d") + " --images clean --mode mask --out " + (tmp / "m2"),
                    tmp / "3.log"), 0);
  for (const Camera& c : ds.cameras)
    EXPECT_EQ(read_file(tmp / ("m1/" + c.name + ".png")), read_file(tmp / ("m2/" + c.name + ".png")));
  // Bad input: exit 2, the file named, nothing written.
  EXPECT_EQ(run_cli("filter --method tophat --task always --data " + (tmp / "d") + " --out " + (tmp / "g"), tmp / "4.log"), 2);  // no images/
  EXPECT_NE(read_file(tmp / "4.log").find("images"), std::string::npos) << read_file(tmp / "4.log");
  EXPECT_EQ(run_cli("filter --method tophat --task always --data " + (tmp / "d") + " --images clean --threshold 2 --out " + (tmp / "g"), tmp / "5.log"), 2);
  EXPECT_NE(read_file(tmp / "5.log").find("threshold"), std::string::npos) << read_file(tmp / "5.log");
  EXPECT_FALSE(fs::exists(tmp / "g"));
}

}  // namespace
}  // namespace weathergs::restoration::aef
