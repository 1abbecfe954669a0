#include "evaluator/metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/json_reader.h"
#include "core/parallel.h"
#include "evaluator/evaluate.h"
#include "evaluator/lpips.h"
#include "tests/core/test_util.h"

namespace weathergs::evaluator {
namespace {

// scikit-image and our SSIM both accumulate in double; agreement to 1e-5 is required.
constexpr double kSsimReferenceTol = 1e-5;
// LPIPS: float32 network; the reference README expects ~1e-6 between implementations, we require 1e-4.
constexpr double kLpipsReferenceTol = 1e-4;
// Pixels are float32 (k/255 rounded to 24 bits), the reference float64: MSE differs by ~1e-7
// relative, i.e. ~5e-7 dB.
constexpr double kPsnrReferenceTolDb = 1e-5;

const std::string kData = WEATHERGS_TEST_DATA_DIR;
const std::string kLpipsRef = std::string(WEATHERGS_SOURCE_DIR) + "/models/lpips/reference/";

Image constant(int w, int h, float v) { return Image(w, h, 3, ColorSpace::kSRGB, v); }

TEST(SsimTest, MatchesScikitImageValidAndThreeDgsSame) {
  JsonReader ref = JsonReader::from_file(kData + "/ssim/ssim_reference.json");
  JsonReader pairs = ref.child("pairs");
  ASSERT_GE(pairs.keys().size(), 5u);
  for (const std::string& name : pairs.keys()) {
    JsonReader p = pairs.child(name);
    Image a = read_image(kData + "/ssim/" + p.get<std::string>("a"));
    Image b = read_image(kData + "/ssim/" + p.get<std::string>("b"));
    SsimOptions valid;
    EXPECT_NEAR(ssim(a, b, valid), p.get<double>("ssim_valid"), kSsimReferenceTol) << name;
    SsimOptions same;
    same.padding = SsimPadding::kSame;
    EXPECT_NEAR(ssim(a, b, same), p.get<double>("ssim_same"), kSsimReferenceTol) << name;
    if (auto ref_psnr = p.get_optional<double>("psnr")) {
      EXPECT_NEAR(psnr(a, b), *ref_psnr, kPsnrReferenceTolDb) << name;
    }
  }
}

TEST(PsnrTest, ByHand) {
  // MSE 0.01 -> PSNR 20 dB exactly (floats 0.5 and 0.6 are off by ~1e-8: tolerance 1e-5 dB).
  EXPECT_NEAR(psnr(constant(7, 5, 0.5f), constant(7, 5, 0.6f)), 20.0, 1e-5);
  // One channel of one pixel off by 1: MSE = 1 / (4 * 3) -> 10 log10(12).
  Image a = constant(2, 2, 0.f), b = a;
  b.at(1, 1, 2) = 1.f;
  EXPECT_NEAR(psnr(a, b), 10 * std::log10(12.0), 1e-12);
  EXPECT_TRUE(std::isinf(psnr(a, a)));
  EXPECT_GT(psnr(a, a), 0);
}

TEST(MetricsTest, IdenticalConstantBlackWhiteStayFinite) {
  for (float v : {0.f, 1.f, 0.37f}) {
    Image c = constant(16, 16, v);
    EXPECT_DOUBLE_EQ(ssim(c, c), 1.0) << v;  // zero variance: C1/C2 keep the ratio 1
    EXPECT_TRUE(std::isinf(psnr(c, c)));
  }
  const double s = ssim(constant(16, 16, 0.f), constant(16, 16, 1.f));
  EXPECT_TRUE(std::isfinite(s));
  EXPECT_NEAR(s, 1e-4 / (1 + 1e-4), 1e-12);  // luminance term only: C1 / (1 + C1)
  EXPECT_DOUBLE_EQ(psnr(constant(16, 16, 0.f), constant(16, 16, 1.f)), 0.0);
}

TEST(MetricsTest, TinyImages) {
  // Smaller than the window: valid padding is a clear error, same padding gives a finite value.
  Image a = constant(5, 7, 0.2f), b = constant(5, 7, 0.3f);
  EXPECT_THROW(ssim(a, b), InputError);
  SsimOptions same;
  same.padding = SsimPadding::kSame;
  EXPECT_TRUE(std::isfinite(ssim(a, b, same)));
  Image p1 = constant(1, 1, 0.2f), p2 = constant(1, 1, 0.9f);
  EXPECT_TRUE(std::isfinite(ssim(p1, p2, same)));
  EXPECT_DOUBLE_EQ(ssim(p1, p1, same), 1.0);
  EXPECT_TRUE(std::isfinite(psnr(p1, p2)));
}

TEST(MetricsTest, MismatchedInputsAreInputErrors) {
  EXPECT_THROW(psnr(constant(4, 4, 0), constant(4, 5, 0)), InputError);
  EXPECT_THROW(ssim(constant(12, 12, 0), constant(13, 12, 0)), InputError);
  Image gray(12, 12, 1);
  EXPECT_THROW(psnr(constant(12, 12, 0), gray), InputError);
}

TEST(MetricsTest, MaskedMetricsUseValidPixelsOnly) {
  Image a = constant(20, 20, 0.5f), b = a;
  Image mask(20, 20, 1, ColorSpace::kLinear, 0.f);
  for (int y = 2; y < 6; ++y)
    for (int x = 3; x < 9; ++x) {
      b.at(x, y, 0) = 1.f;  // damage only under the mask
      mask.at(x, y) = 1.f;
    }
  EXPECT_TRUE(std::isinf(psnr(a, b, &mask)));
  EXPECT_FALSE(std::isinf(psnr(a, b)));
  // Masked MSE divides by valid pixels, not by all: damage one valid pixel by 0.5 in one channel.
  b.at(15, 15, 1) = 1.f;
  const double valid_values = (400.0 - 24.0) * 3.0;
  EXPECT_NEAR(psnr(a, b, &mask), 10 * std::log10(valid_values / 0.25), 1e-9);
  // SSIM over valid centres is below 1 (the damaged pixel) and the masked centres are excluded.
  const double s = ssim(a, b, {}, &mask);
  EXPECT_LT(s, 1.0);
  EXPECT_GT(s, ssim(a, b));
  Image all(20, 20, 1, ColorSpace::kLinear, 1.f);
  EXPECT_THROW(psnr(a, b, &all), InputError);
  EXPECT_THROW(ssim(a, b, {}, &all), InputError);
}

TEST(MetricsTest, SameBitsWithOneOrTwoThreads) {
  Image a = read_image(kData + "/ssim/odd_97x131_a.png"), b = read_image(kData + "/ssim/odd_97x131_b.png");
  set_num_threads(1);
  const double s1 = ssim(a, b), p1 = psnr(a, b);
  set_num_threads(2);
  const double s2 = ssim(a, b), p2 = psnr(a, b);
  set_num_threads(0);
  EXPECT_EQ(s1, s2);
  EXPECT_EQ(p1, p2);
}

TEST(LpipsTest, ReproducesOfficialReferenceValues) {
  Lpips lpips(find_lpips_model(testing::lpips_model_search()));
  Image ref = read_image(kLpipsRef + "ex_ref.png");
  EXPECT_NEAR(lpips.distance(ref, read_image(kLpipsRef + "ex_p0.png")), 0.721881, kLpipsReferenceTol);
  EXPECT_NEAR(lpips.distance(ref, read_image(kLpipsRef + "ex_p1.png")), 0.137566, kLpipsReferenceTol);
  EXPECT_NEAR(lpips.distance(read_image(kLpipsRef + "synthetic_a_97x131.png"),
                             read_image(kLpipsRef + "synthetic_b_97x131.png")),
              0.05471683, kLpipsReferenceTol);
  EXPECT_DOUBLE_EQ(lpips.distance(ref, ref), 0.0);
  // Symmetric up to float rounding.
  EXPECT_NEAR(lpips.distance(read_image(kLpipsRef + "ex_p0.png"), ref), 0.721881, kLpipsReferenceTol);
}

TEST(LpipsTest, ExtremeAndTinyInputs) {
  Lpips lpips(find_lpips_model(testing::lpips_model_search()));
  const double d = lpips.distance(constant(64, 64, 0.f), constant(64, 64, 1.f));
  EXPECT_TRUE(std::isfinite(d));
  EXPECT_GT(d, 0);
  EXPECT_DOUBLE_EQ(lpips.distance(constant(64, 64, 0.f), constant(64, 64, 0.f)), 0.0);
  EXPECT_TRUE(std::isfinite(lpips.distance(constant(kLpipsMinSide, kLpipsMinSide, 0.2f),
                                           constant(kLpipsMinSide, kLpipsMinSide, 0.8f))));
  EXPECT_THROW(lpips.distance(constant(30, 64, 0.f), constant(30, 64, 0.f)), InputError);
  EXPECT_THROW(lpips.distance(constant(1, 1, 0.f), constant(1, 1, 0.f)), InputError);
}

TEST(LpipsTest, MissingModelSaysWhereItLooked) {
  try {
    find_lpips_model({"/nonexistent/lpips.onnx", "/nonexistent_dir"});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/lpips.onnx"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("/nonexistent_dir"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("--no-lpips"), std::string::npos);
  }
  EXPECT_THROW(find_lpips_model({}), InputError);
  // The first candidate that holds the model wins; a folder or the file itself both work.
  std::vector<std::string> search = {"/nonexistent_dir"};
  for (const std::string& s : testing::lpips_model_search()) search.push_back(s);
  EXPECT_NO_THROW(find_lpips_model(search));
  EXPECT_EQ(find_lpips_model({find_lpips_model(search)}), find_lpips_model(search));
}

TEST(ScorePairTest, SixteenBitPngAndExrInputs) {
  testing::TempDir dir;
  Image a = read_image(kData + "/ssim/odd_97x131_a.png");
  write_image(dir / "a16.png", a, {PixelFormat::kUInt16, {}});
  write_image(dir / "a.exr", to_linear(a));
  ScoringOptions o;
  o.lpips = false;
  // Same content through 16-bit PNG and linear EXR: identical after 8-bit quantization.
  MetricValues m16 = score_pair(read_image(dir / "a16.png"), a, o, nullptr, nullptr, "16-bit");
  MetricValues mexr = score_pair(read_image(dir / "a.exr"), a, o, nullptr, nullptr, "exr");
  EXPECT_TRUE(std::isinf(m16.psnr));
  EXPECT_TRUE(std::isinf(mexr.psnr));
  EXPECT_DOUBLE_EQ(mexr.ssim, 1.0);
  // Non-finite values never reach the metrics.
  Image bad = to_linear(a);
  bad.data[100] = NAN;
  EXPECT_THROW(score_pair(bad, a, o, nullptr, nullptr, "nan"), InputError);
}

}  // namespace
}  // namespace weathergs::evaluator
