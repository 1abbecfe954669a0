// The results format of docs/formats.md ("weathergs-results", version 1), read strictly.
//
// PSNR of identical images is +infinity. JSON has no infinity, so it is written as
// "psnr": null together with "psnr_infinite": true (documented in docs/evaluator.md); readers turn
// that back into +inf. A skipped LPIPS (--no-lpips) is "lpips": null and protocol.lpips = null.
// The dataset scored against is recorded as "dataset_identity" (docs/formats.md, "Dataset identity");
// results written before it was recorded have none and read as an unknown dataset.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/dataset_identity.h"
#include "core/json_reader.h"

namespace weathergs::evaluator {

struct MetricValues {
  double psnr = 0;                 // may be +inf
  double ssim = 0;
  std::optional<double> lpips;     // absent when LPIPS was skipped
};

inline constexpr const char* kLpipsTruthFilled = "truth_filled";

struct Protocol {
  std::string ssim = "gaussian11_sigma1.5_valid";
  std::optional<std::string> lpips = std::string("alex_v0.1");  // nullopt: skipped (--no-lpips)
  bool quantize_uint8 = true;
  std::string split = "test";
  std::optional<std::string> mask;  // mask folder name when masked metrics were used
  // The dataset folder scored against when it is not clean/ (e.g. "targets/no_particles" to score a
  // particle filter); nullopt = clean/, the benchmark's ground truth. Optional in results.json.
  std::optional<std::string> ground_truth;
  // How LPIPS treats the mask (a network sees whole images, not pixels): kLpipsTruthFilled, the masked
  // pixels of the render replaced by the ground truth's, so that only valid pixels can differ. Written
  // whenever `mask` is; absent in a masked result made before LPIPS was masked (it scored whole images).
  std::optional<std::string> lpips_mask;
  bool operator==(const Protocol& o) const {
    return ssim == o.ssim && lpips == o.lpips && quantize_uint8 == o.quantize_uint8 && split == o.split &&
           mask == o.mask && ground_truth == o.ground_truth && lpips_mask == o.lpips_mask;
  }
  std::string to_string() const;
};

// What results.json records of the dataset it was scored against.
// {"scheme": DatasetIdentity::kScheme, "sha256", "file_count"[, "differs_from_recorded"]}.
struct ScoredDataset {
  std::string sha256;     // DatasetIdentity::sha256 of the files when they were scored
  size_t file_count = 0;  // how many files (and pseudo-files) it covers; the list is not written
  // Set only when the files no longer matched the identity their dataset.json records and scoring was
  // allowed anyway (evaluate --allow-changed-dataset): that record's sha256 and the first difference.
  std::optional<std::string> recorded_sha256, first_difference;
};

struct Results {
  std::string method, dataset, scene, weather;
  Protocol protocol;
  MetricValues metrics;  // mean over views of the per-view values
  std::vector<std::pair<std::string, MetricValues>> per_view;  // split order
  Json method_info = Json::object();
  std::string sha256_renders, sha256_ground_truth;
  std::optional<ScoredDataset> dataset_identity;  // nullopt: scored before identities were recorded
};

// Whether two results cannot count as scored on the same data: their identities differ, or only one
// records one. Two results that both record none are not known to differ (as before identities).
bool dataset_identity_differs(const Results& a, const Results& b);
// The identity's first 12 hex digits, for tables and messages; "unknown" when none is recorded.
std::string short_dataset_identity(const Results& r);
// The whole sha256, or "none recorded".
std::string dataset_identity_text(const Results& r);

// Mean of per-view values (PSNR averaged per view, as 3DGS reports it; +inf if any view is +inf).
MetricValues mean_metrics(const std::vector<std::pair<std::string, MetricValues>>& per_view);

// {"psnr", "ssim", "lpips"} (+ "psnr_infinite": true when PSNR is +inf, with "psnr": null).
Json metrics_to_json(const MetricValues& m);
Json protocol_to_json(const Protocol& p);  // results.json's "protocol" block
Json results_to_json(const Results& r);
Results results_from_json(const JsonReader& reader);
Results read_results(const std::string& path);
void write_results(const std::string& path, const Results& r);  // atomic

// Formats a metric for text output: "+inf" for infinite PSNR, fixed decimals otherwise.
std::string format_metric(double v, int decimals);

}  // namespace weathergs::evaluator
