// Export of a scored run in NerfBaselines' evaluation layout, so that its tools (tables, web page,
// `nerfbaselines evaluate` on the predictions) read our results.
//
//   OUT/results.json                 NerfBaselines' evaluation results: "metrics" (mean over views,
//                                    rounded to 5 decimals), "metrics_raw" (per view, base64 of
//                                    little-endian float32 in sorted file order), "metrics_sha256",
//                                    "predictions_sha256" / "ground_truth_sha256" (sha256 of the
//                                    concatenated PNG files in sorted order), "evaluation_protocol",
//                                    "nb_info", "render_dataset_metadata"
//   OUT/predictions/info.json        the nb_info of the renders
//   OUT/predictions/color/<view>.png      the render, as scored (8-bit sRGB)
//   OUT/predictions/gt-color/<view>.png   the ground truth, as scored (8-bit sRGB)
//
// The layout and hashes follow nerfbaselines/io.py (serialize_evaluation_results,
// get_predictions_sha, get_metrics_hash). Our protocol (8-bit sRGB, SSIM Gaussian 11 / sigma 1.5 on
// valid pixels, LPIPS AlexNet v0.1, PSNR averaged per image) is NerfBaselines' "default" protocol, so
// results.json names that; the exact weathergs protocol is kept under nb_info.weathergs.
#pragma once

#include <string>

#include "evaluator/results.h"

namespace weathergs::evaluator {

struct NerfBaselinesExportOptions {
  std::string results;   // a weathergs results.json
  std::string renders;   // the renders it scored (<view>.png)
  std::string dataset;   // the dataset it was scored against (its ground truth folder per the protocol)
  std::string out;       // the export folder (written atomically; replaced only with force)
  bool force = false;
  void validate() const;  // InputError naming the field
};

struct NerfBaselinesExport {
  Json results;  // what OUT/results.json holds
  int views = 0;
};

// InputError when the run cannot be expressed in NerfBaselines' layout (masked metrics, an infinite
// PSNR, renders or ground truth that do not match results.json's hashes).
NerfBaselinesExport export_nerfbaselines(const NerfBaselinesExportOptions& options);

// The pieces, public for tests: base64 of little-endian float32 values (NerfBaselines' _encode_values)
// and its metrics hash (get_metrics_hash: sorted keys, each key's values sorted).
std::string encode_float32_base64(const std::vector<double>& values);
std::string nerfbaselines_metrics_sha256(const std::map<std::string, std::vector<double>>& metrics_lists);

}  // namespace weathergs::evaluator
