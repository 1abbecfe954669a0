// Scoring flags shared by `compare` and `evaluate`, so both read and record the protocol the same way.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "apps/resources.h"
#include "evaluator/evaluate.h"

namespace weathergs::cli {

struct ScoringFlags {
  bool no_lpips = false;
  bool no_quantize = false;
  std::string lpips_model;
  std::string ssim_padding = "valid";

  void add_to(CLI::App* app) {
    app->add_flag("--no-lpips", no_lpips, "Skip LPIPS (recorded as lpips: null in the protocol)");
    app->add_option("--lpips-model", lpips_model,
                    "LPIPS ONNX model (file or folder); default: $WEATHERGS_LPIPS_MODEL, then the install's "
                    "share/weathergs/models/lpips (shipped with weathergs)");
    app->add_option("--ssim-padding", ssim_padding,
                    "SSIM border convention: valid (scikit-image, default) or same (zero padding, 3DGS)")
        ->check(CLI::IsMember({"valid", "same"}));
    app->add_flag("--no-quantize", no_quantize,
                  "Score float values instead of quantizing both images to 8-bit sRGB first");
  }
  evaluator::ScoringOptions options() const {
    evaluator::ScoringOptions o;
    o.lpips = !no_lpips;
    o.quantize_uint8 = !no_quantize;
    if (o.lpips) o.lpips_model_search = lpips_model_search(lpips_model);
    o.ssim.padding = ssim_padding == "same" ? evaluator::SsimPadding::kSame : evaluator::SsimPadding::kValid;
    return o;
  }
};

}  // namespace weathergs::cli
