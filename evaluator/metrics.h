// Full-reference image metrics: PSNR and SSIM (LPIPS is in lpips.h).
//
// Inputs are RGB images with values in [0, 1] (data range L = 1). Masks follow docs/formats.md:
// a 1-channel image where 1 means "effect present, exclude this pixel"; metrics are computed over the
// remaining (valid) pixels only, never by multiplying the images by the mask.
#pragma once

#include <string>

#include "core/image.h"

namespace weathergs::evaluator {

// PSNR = 10 log10(L^2 / MSE), MSE over all valid pixels and channels, accumulated in double.
// Identical images give +infinity (the caller decides how to print it; see docs/evaluator.md).
// Throws InputError if the mask excludes every pixel.
double psnr(const Image& a, const Image& b, const Image* exclude_mask = nullptr);
double mse(const Image& a, const Image& b, const Image* exclude_mask = nullptr);

enum class SsimPadding {
  // Only positions where the whole 11x11 window lies inside the image (scikit-image with
  // gaussian_weights=True, sigma=1.5, use_sample_covariance=False; torchmetrics; pytorch_msssim).
  kValid,
  // Every pixel, the window zero-padded at the border (the 3DGS training and metrics code).
  kSame,
};

struct SsimOptions {
  SsimPadding padding = SsimPadding::kValid;
  double sigma = 1.5;       // Gaussian window standard deviation (pixels)
  int radius = 5;           // window is (2 radius + 1)^2 = 11x11 (scikit-image: int(3.5 sigma + 0.5))
  double k1 = 0.01, k2 = 0.03;
  double data_range = 1.0;  // L: C1 = (k1 L)^2, C2 = (k2 L)^2

  void validate() const;    // InternalError on nonsense (options come from code, not users)
  std::string protocol_name() const;  // "gaussian11_sigma1.5_valid"
};

// Mean SSIM: per channel, the mean of the SSIM map, then the mean over channels. With a mask, the map
// is averaged over valid window centers only (a window centred on a valid pixel still sees its masked
// neighbours; see docs/evaluator.md). kValid on an image smaller than the window throws InputError.
double ssim(const Image& a, const Image& b, const SsimOptions& options = {},
            const Image* exclude_mask = nullptr);

// Checks that a and b (and the mask, if any) can be compared; names `where` in the error.
void require_comparable(const Image& a, const Image& b, const Image* exclude_mask, const std::string& where);

}  // namespace weathergs::evaluator
