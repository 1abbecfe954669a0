#include "core/image.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "core/atomic_file.h"
#include "tests/core/test_util.h"

namespace weathergs {
namespace {

using testing::TempDir;

TEST(SrgbTest, MatchesStandardAndRoundTrips) {
  // IEC 61966-2-1 reference points.
  EXPECT_FLOAT_EQ(srgb_to_linear(0.f), 0.f);
  EXPECT_FLOAT_EQ(srgb_to_linear(1.f), 1.f);
  EXPECT_NEAR(srgb_to_linear(0.5f), 0.2140411f, 1e-6f);
  EXPECT_NEAR(srgb_to_linear(0.04045f), 0.04045f / 12.92f, 1e-7f);
  EXPECT_NEAR(linear_to_srgb(0.0031308f), 0.0031308f * 12.92f, 1e-6f);
  EXPECT_NEAR(linear_to_srgb(0.18f), 0.4613561f, 1e-6f);
  // Every 8-bit code survives sRGB -> linear -> sRGB -> 8 bit.
  for (int i = 0; i < 256; ++i) {
    float v = i / 255.f;
    EXPECT_EQ(int(std::floor(linear_to_srgb(srgb_to_linear(v)) * 255.f + 0.5f)), i);
  }
}

TEST(ImageTest, Png8And16RoundTrip) {
  TempDir dir;
  Image img(7, 5, 3);
  for (size_t i = 0; i < img.data.size(); ++i) img.data[i] = float(i % 256) / 255.f;
  write_image(dir / "a.png", img);
  Image back = read_image(dir / "a.png");
  ASSERT_TRUE(back.same_shape(img));
  EXPECT_EQ(back.space, ColorSpace::kSRGB);
  for (size_t i = 0; i < img.data.size(); ++i) EXPECT_NEAR(back.data[i], img.data[i], 1e-6f);

  Image fine(3, 2, 1);
  fine.data = {0.f, 1.f / 65535.f, 0.5f, 0.25f, 1.f, 12345.f / 65535.f};
  write_image(dir / "b.png", fine, {PixelFormat::kUInt16, {}});
  Image fine_back = read_image(dir / "b.png");
  for (size_t i = 0; i < fine.data.size(); ++i) EXPECT_NEAR(fine_back.data[i], fine.data[i], 0.5f / 65535.f);
}

TEST(ImageTest, ExrIsLinearAndDepthChannelZ) {
  TempDir dir;
  Image depth(4, 3, 1, ColorSpace::kLinear);
  for (size_t i = 0; i < depth.data.size(); ++i) depth.data[i] = 0.5f + float(i);
  depth.data[5] = INFINITY;  // background
  depth.data[6] = 65504.f;
  write_depth(dir / "d.exr", depth);
  Image back = read_depth(dir / "d.exr");
  ASSERT_TRUE(back.same_shape(depth));
  for (size_t i = 0; i < depth.data.size(); ++i) EXPECT_EQ(back.data[i], depth.data[i]);
}

// Bad-input corpus: a non-positive depth must be refused, since `weather` would otherwise silently
// leave the fog out of those pixels (exit 0).
TEST(ImageTest, NonPositiveDepthIsAnInputErrorNamingThePixel) {
  TempDir dir;
  for (const float bad : {-2.5f, 0.f, -INFINITY}) {
    Image depth(4, 3, 1, ColorSpace::kLinear, 3.f);
    depth.at(2, 1, 0) = bad;
    write_depth(dir / "d.exr", depth);
    try {
      read_depth(dir / "d.exr");
      FAIL() << "expected InputError for depth " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("d.exr"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("pixel (2, 1)"), std::string::npos) << e.what();
    }
  }
}

TEST(ImageTest, SameImageSameBytes) {
  TempDir dir;
  Image img(5, 4, 3, ColorSpace::kLinear, 0.25f);
  write_image(dir / "a.exr", img);
  write_image(dir / "b.exr", img);
  EXPECT_EQ(read_file(dir / "a.exr"), read_file(dir / "b.exr"));
  Image png(5, 4, 3, ColorSpace::kSRGB, 0.25f);
  write_image(dir / "a.png", png);
  write_image(dir / "b.png", png);
  EXPECT_EQ(read_file(dir / "a.png"), read_file(dir / "b.png"));
}

TEST(ImageTest, NonFiniteExrIsAClearError) {
  TempDir dir;
  Image img(2, 2, 3, ColorSpace::kLinear, 0.5f);
  img.at(1, 0, 2) = NAN;
  write_image(dir / "nan.exr", img);
  try {
    read_image(dir / "nan.exr");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("NaN"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("nan.exr"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("(1, 0)"), std::string::npos) << e.what();
  }
  img.at(1, 0, 2) = INFINITY;
  write_image(dir / "inf.exr", img);
  EXPECT_THROW(read_image(dir / "inf.exr"), InputError);
}

TEST(ImageTest, BadFilesAreInputErrors) {
  TempDir dir;
  EXPECT_THROW(read_image(dir / "missing.png"), InputError);
  write_file_atomic(dir / "corrupt.png", "this is not a png at all");
  EXPECT_THROW(read_image(dir / "corrupt.png"), InputError);
  // A valid PNG cut in half.
  Image img(64, 64, 3, ColorSpace::kSRGB, 0.3f);
  for (size_t i = 0; i < img.data.size(); ++i) img.data[i] = float((i * 7919) % 256) / 255.f;
  write_image(dir / "full.png", img);
  std::string bytes = read_file(dir / "full.png");
  write_file_atomic(dir / "trunc.png", bytes.substr(0, bytes.size() / 2));
  EXPECT_THROW(read_image(dir / "trunc.png"), InputError);
}

TEST(ImageTest, WriteIsAtomicAndLeavesNoTempFiles) {
  TempDir dir;
  Image img(3, 3, 3, ColorSpace::kSRGB, 0.5f);
  write_image(dir / "x.png", img);
  EXPECT_EQ(testing::count_entries(dir.path()), 1);
  write_image(dir / "x.png", img);  // over an existing file: still one entry
  EXPECT_EQ(testing::count_entries(dir.path()), 1);
  EXPECT_THROW(write_image(dir / "x.png/y.png", img), InputError);  // a file where a folder must be
  EXPECT_EQ(testing::count_entries(dir.path()), 1);
}

TEST(ImageTest, QuantizeAndMask) {
  Image img(2, 1, 3, ColorSpace::kSRGB);
  img.data = {0.f, 0.5f, 1.f, -0.2f, 1.7f, 0.50196f};
  Image q = quantize_uint8(img);
  EXPECT_FLOAT_EQ(q.data[1], 128.f / 255.f);  // 127.5 rounds half up
  EXPECT_FLOAT_EQ(q.data[3], 0.f);
  EXPECT_FLOAT_EQ(q.data[4], 1.f);
  TempDir dir;
  Image m(3, 1, 1, ColorSpace::kLinear);
  m.data = {0.f, 0.7f, 1.f};
  write_mask(dir / "m.png", m);
  Image mb = read_mask(dir / "m.png");
  EXPECT_EQ(mb.data, (std::vector<float>{0.f, 1.f, 1.f}));
}

}  // namespace
}  // namespace weathergs
