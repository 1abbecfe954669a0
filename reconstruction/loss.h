// The 3DGS photometric loss (1 - lambda) L1 + lambda (1 - SSIM) with an optional validity mask, and
// its gradient with respect to the rendered image.
//
// SSIM is the 3DGS training SSIM: 11x11 Gaussian window (sigma 1.5), zero 'same' padding (the window
// is not renormalized at the image border), C1 = 0.01^2, C2 = 0.03^2, per channel.
//
// Masks. Masked (invalid) pixels give no gradient: L1 is averaged over the valid pixels only, and the
// SSIM map is averaged over valid pixel centres only. A window around a valid pixel may straddle the
// mask border; there the render's masked pixels are replaced by the target's, so the masked part of
// the window counts as perfectly matched, carries no information about the render and receives
// exactly zero gradient. Without a mask this is the reference loss exactly.
//
// MaskNormalization::kReference instead follows the WeatherGS release as it is specified here: the
// target's masked pixels are replaced by the render (held constant) and both terms are averaged over
// ALL pixels. Masked pixels then add nothing to L1 but still take part in the SSIM windows of their
// neighbours and receive an SSIM gradient, and the loss of a heavily masked view is scaled down by
// its valid fraction. It equals the unmasked loss against that composited target (tested).
#pragma once

#include <cstdint>
#include <vector>

namespace weathergs::reconstruction {

constexpr double kLambdaDssim = 0.2;  // reference lambda_dssim
constexpr int kSsimWindow = 11;
constexpr double kSsimSigma = 1.5;
constexpr double kSsimC1 = 0.01 * 0.01;
constexpr double kSsimC2 = 0.03 * 0.03;

template <typename T>
struct LossValue {
  T loss = 0;       // (1 - lambda) l1 + lambda (1 - ssim)
  T l1 = 0;         // mean |render - target| over valid pixels and channels
  T ssim = 0;       // mean SSIM over valid pixel centres and channels
  T mse = 0;        // mean squared error over valid pixels and channels (for PSNR)
  int64_t valid_pixels = 0;
};

enum class MaskNormalization { kValid, kReference };
const char* to_string(MaskNormalization m);  // "valid" | "reference"

// Normalized 1D window of the SSIM (11 taps, sigma 1.5).
std::vector<double> ssim_window_1d();

// render, target: H x W x 3 interleaved. invalid: H x W, nonzero where the pixel is masked out; may be
// null. If v_render is not null it receives dL/drender (H x W x 3; exactly 0 on masked pixels). With
// no valid pixel the loss is 0 and the gradient 0.
template <typename T>
LossValue<T> photometric_loss(const std::vector<T>& render, const std::vector<T>& target,
                              const std::vector<uint8_t>* invalid, int width, int height, T lambda_dssim,
                              std::vector<T>* v_render,
                              MaskNormalization normalization = MaskNormalization::kValid);

// Mean SSIM of two H x W x 3 images over all pixels (same conventions), for tests and reports.
template <typename T>
T ssim_mean(const std::vector<T>& a, const std::vector<T>& b, int width, int height);

// PSNR in dB of a mean squared error of [0, 1] values; capped at 100 dB for a perfect match.
double psnr_from_mse(double mse);

}  // namespace weathergs::reconstruction
