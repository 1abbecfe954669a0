// The dataset layout, the background-depth rule, the thin lens and JsonReader's shared helpers: the
// one home of each (docs/architecture.md, "One home per concept").
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/image.h"
#include "core/json_reader.h"
#include "core/thin_lens.h"
#include "tests/core/test_util.h"

namespace weathergs {
namespace {

enum class Mode { kA, kB };
const char* to_string(Mode m) { return m == Mode::kA ? "a" : "b"; }

template <typename F>
std::string input_error(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(DatasetLayoutTest, PathsOfEveryKind) {
  Dataset d;
  d.root = "/data/pool_rain";
  EXPECT_EQ(d.path(ImageKind::kImages, "007"), "/data/pool_rain/images/007.png");
  EXPECT_EQ(d.path(ImageKind::kClean, "007"), "/data/pool_rain/clean/007.png");
  EXPECT_EQ(d.path(ImageKind::kDepth, "007"), "/data/pool_rain/depth/007.exr");
  EXPECT_EQ(d.path(ImageKind::kLensMask, "007"), "/data/pool_rain/masks/lens/007.png");
  EXPECT_EQ(d.path(ImageKind::kParticleMask, "007"), "/data/pool_rain/masks/particles/007.png");
  EXPECT_EQ(d.layer_path("particle_alpha", "007"), "/data/pool_rain/layers/particle_alpha/007.exr");
  EXPECT_EQ(d.file(layout::kSparseModelDir), "/data/pool_rain/sparse/0");
  EXPECT_EQ(d.dir(ImageKind::kLensMask), "/data/pool_rain/masks/lens");
}

TEST(DatasetLayoutTest, CleanIfPresentElseImages) {
  testing::TempDir dir;
  Dataset d;
  d.root = dir.path();
  std::filesystem::create_directories(d.dir(ImageKind::kImages));
  EXPECT_FALSE(d.has(ImageKind::kClean));
  EXPECT_EQ(d.clean_or_input_path("001"), d.path(ImageKind::kImages, "001"));
  std::filesystem::create_directories(d.dir(ImageKind::kClean));
  EXPECT_EQ(d.clean_or_input_path("001"), d.path(ImageKind::kClean, "001"));
}

TEST(DatasetLayoutTest, BackgroundDepthHasOneDefinition) {
  // docs/formats.md: background is +inf or any value >= 1e9.
  EXPECT_TRUE(is_background_depth(std::numeric_limits<float>::infinity()));
  EXPECT_TRUE(is_background_depth(1e9f));
  EXPECT_TRUE(is_background_depth(3e9f));
  EXPECT_FALSE(is_background_depth(65504.f));  // EEVEE's raw background is converted by capture
  EXPECT_FALSE(is_background_depth(999.f));
  EXPECT_FALSE(is_background_depth(0.f));
}

TEST(ThinLensTest, CircleOfConfusionFollowsTheThinLens) {
  Camera c;
  c.name = "v";
  c.fx = 140;
  EXPECT_FALSE(thin_lens_of(c).has_value());  // no lens data: a pinhole
  c.f_number = 8;
  c.focal_length_mm = 4;
  c.focus_distance_m = 3;
  const ThinLens lens = *thin_lens_of(c);
  // fx * (f / N) * |z - s| / (z (s - f)) with f = 4 mm, N = 8, s = 3 m, z = 3 cm.
  EXPECT_NEAR(lens.coc_diameter_px(c.fx, 0.03), 140 * 0.5e-3 * 2.97 / (0.03 * 2.996), 1e-12);
  EXPECT_DOUBLE_EQ(lens.coc_radius_px(c.fx, 0.03), 0.5 * lens.coc_diameter_px(c.fx, 0.03));
  EXPECT_DOUBLE_EQ(lens.coc_diameter_px(c.fx, 3.0), 0.0);  // in focus
  EXPECT_DOUBLE_EQ(lens.coc_diameter_px(c.fx, 0.0), 0.0);  // degenerate depth: no blur, no NaN
  EXPECT_TRUE(std::isfinite(lens.coc_diameter_px(c.fx, 1e-30)));
  // Bad lens data: an error naming the view and the field.
  c.focus_distance_m = 0.002;  // closer than the focal length
  EXPECT_NE(input_error([&] { thin_lens_of(c); }).find("focus_distance_m"), std::string::npos);
  c.focus_distance_m = std::numeric_limits<double>::infinity();
  EXPECT_NE(input_error([&] { thin_lens_of(c); }).find("view 'v'"), std::string::npos);
  c.focus_distance_m = 3;
  c.f_number = 0;
  EXPECT_NE(input_error([&] { thin_lens_of(c); }).find("f_number"), std::string::npos);
}

TEST(JsonReaderHelpersTest, OneGrammarAndOneWording) {
  const Json doc = Json::parse(R"({"n": 5, "big": 1e6, "v3": [1, 2, 3], "v2": [1], "r1": 0.5, "r2": [0.5, 3],
                                   "rbad": [3, 0.5], "mode": "b", "mbad": "c", "s": "x"})");
  JsonReader r(doc, "spec.json");
  EXPECT_EQ(r.get_number("n", 0, 10), 5);
  EXPECT_EQ(r.get_number_or("missing", 7, 0, 10), 7);
  EXPECT_EQ(input_error([&] { r.get_number("big", 0, 10); }), "spec.json:/big: expected a number in [0, 10], got 1e+06");
  EXPECT_EQ((r.get_array<3>("v3")), (std::array<double, 3>{1, 2, 3}));
  EXPECT_NE(input_error([&] { r.get_array<3>("v2"); }).find("expected an array of 3 numbers, got 1 elements"),
            std::string::npos);
  EXPECT_EQ(input_error([&] { r.get_array<3>("v3", 0, 2); }), "spec.json:/v3/2: expected a number in [0, 2], got 3");
  EXPECT_EQ(r.get_range_or("r1", {0, 0}), (std::array<double, 2>{0.5, 0.5}));
  EXPECT_EQ(r.get_range_or("r2", {0, 0}), (std::array<double, 2>{0.5, 3}));
  EXPECT_EQ(r.get_range_or("absent", {1, 2}), (std::array<double, 2>{1, 2}));
  EXPECT_EQ(input_error([&] { r.get_range_or("rbad", {0, 0}); }),
            "spec.json:/rbad: expected [min, max] with min <= max, got [3, 0.5]");
  EXPECT_NE(input_error([&] { r.get_range_or("s", {0, 0}); }).find("expected a number or [min, max]"), std::string::npos);
  EXPECT_EQ(r.get_enum("mode", {Mode::kA, Mode::kB}), Mode::kB);
  EXPECT_EQ(r.get_enum_or("nomode", Mode::kA, {Mode::kA, Mode::kB}), Mode::kA);
  EXPECT_EQ(input_error([&] { r.get_enum("mbad", {Mode::kA, Mode::kB}); }),
            "spec.json:/mbad: expected one of \"a\", \"b\", got \"c\"");
  r.finish();  // every key above was read
}

// Found by fuzz_dataset, fuzz_scene_spec and fuzz_results (docs/reliability.md): a number beyond
// double's range made nlohmann throw out_of_range, which escaped as an internal error.
TEST(JsonReaderHelpersTest, NumberOverflowIsAnInputError) {
  testing::TempDir dir;
  for (const char* text : {R"({"format": 701e1701})", R"({"views": [{"fx": 33E89781}]})", "[4444e4444]", "-1e999"}) {
    write_file_atomic(dir / "x.json", text);
    const std::string msg = input_error([&] { read_json_file(dir / "x.json"); });
    EXPECT_NE(msg.find("x.json"), std::string::npos) << text;
    EXPECT_NE(msg.find("malformed JSON"), std::string::npos) << text;
  }
}

// Found by fuzz_image: a PNG header may claim any size; the reader refuses absurd ones before it
// allocates (a 100000 x 100000 RGB float image would be 120 GB).
uint32_t crc32(const std::string& bytes) {
  uint32_t c = 0xffffffffu;
  for (unsigned char b : bytes) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
  }
  return ~c;
}

std::string be32(uint32_t v) {
  return {char(v >> 24), char((v >> 16) & 0xff), char((v >> 8) & 0xff), char(v & 0xff)};
}

TEST(ImageReaderTest, AbsurdHeaderSizeIsAnInputErrorBeforeAllocating) {
  testing::TempDir dir;
  const std::string ihdr = "IHDR" + be32(100000) + be32(100000) + std::string("\x08\x02\x00\x00\x00", 5);
  const std::string idat = "IDAT" + std::string("\x78\x9c\x03\x00\x00\x00\x00\x01", 8);  // empty zlib stream
  const std::string png = std::string("\x89PNG\r\n\x1a\n", 8) + be32(13) + ihdr + be32(crc32(ihdr)) + be32(8) + idat +
                          be32(crc32(idat)) + be32(0) + "IEND" + be32(crc32("IEND"));
  write_file_atomic(dir / "huge.png", png);
  const std::string msg = input_error([&] { read_image(dir / "huge.png"); });
  EXPECT_NE(msg.find("huge.png"), std::string::npos) << msg;
  EXPECT_NE(msg.find("100000x100000"), std::string::npos) << msg;
}

}  // namespace
}  // namespace weathergs
