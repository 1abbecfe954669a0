// Scoring a method's renders against a dataset's clean ground truth (`weathergs evaluate`).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/dataset.h"
#include "core/dataset_layout.h"
#include "core/image.h"
#include "evaluator/lpips.h"
#include "evaluator/metrics.h"
#include "evaluator/results.h"

namespace weathergs::evaluator {

// How two images are scored (the evaluation protocol). Every choice is recorded in the results.
struct ScoringOptions {
  bool quantize_uint8 = true;  // quantize both images to 8-bit sRGB first (as NerfBaselines does)
  SsimOptions ssim;            // default: 11x11 Gaussian, sigma 1.5, valid padding
  bool lpips = true;           // false: skipped explicitly (--no-lpips), recorded as lpips: null
  std::vector<std::string> lpips_model_search;  // where to look for the model, in order (lpips.h)
};

// Checks, before any long work, that scoring can run: with lpips on, the model is found and loads.
// InputError listing where it looked and how to provide the model (or skip it with --no-lpips).
void check_scoring_resources(const ScoringOptions& options);

// Scores one pair (sRGB or linear, any 1..4 channels: converted to RGB sRGB first). `lpips` may be
// null when options.lpips is false. `where` names the pair in errors.
MetricValues score_pair(const Image& render, const Image& ground_truth, const ScoringOptions& options,
                        Lpips* lpips, const Image* exclude_mask, const std::string& where);

struct EvaluateOptions {
  std::string gt_dataset;      // dataset folder with clean/<view>.png
  std::string renders_dir;     // <renders>/<view>.png for every view of the split (+ optional info.json)
  std::string method;          // empty: taken from <renders>/info.json "method"
  std::string split = "test";
  ImageKind ground_truth = ImageKind::kClean;  // which of the dataset's image folders is the truth
  std::optional<std::string> mask_dir;  // masks (255 = exclude) named <view>.png
  ScoringOptions scoring;
  // Score although the dataset's files no longer match the identity its dataset.json records; the
  // difference is then written into results.json (dataset_identity.differs_from_recorded).
  bool allow_changed_dataset = false;

  // InputError naming the field and the rule (gt_dataset, renders_dir, split required; ground truth
  // must be an image kind: clean or images).
  void validate() const;
};

// The protocol results scored with these options record (results.json's "protocol").
Protocol scoring_protocol(const EvaluateOptions& options);

// The identity of the dataset's files as results.json records it (docs/formats.md, "Dataset
// identity"). When dataset.json records an identity that the files no longer match: InputError naming
// the dataset, both hashes and the first differing file, unless allow_changed, which keeps the
// difference in the returned record instead.
ScoredDataset identify_dataset(const Dataset& dataset, bool allow_changed);

// Scores every view of the split in parallel, after checking the dataset's identity (identify_dataset). Missing or extra renders, unreadable images, size
// mismatches and missing masks are InputErrors naming the view.
Results evaluate(const EvaluateOptions& options);

// The hash results.json records for a set of files: sha256 over "view sha256(file)\n" lines in split
// order (names and contents both count).
std::string hash_view_files(const std::vector<std::string>& views, const std::vector<std::string>& paths);

}  // namespace weathergs::evaluator
