// `weathergs filter`: the particle filter over every view of a dataset (docs/restoration.md).
#pragma once

#include <string>
#include <vector>

#include "core/dataset_layout.h"
#include "restoration/particle_filter.h"

namespace weathergs::restoration {

// restore: <out>/<view>.png are the filtered images (train 3DGS on them: train --images-dir) and
//          <out>/masks/<view>.png the particle masks; mask: <out>/<view>.png are the particle masks
//          only (255 = particle: train on the raw pixels elsewhere with train --masks-dir).
enum class FilterMode { kRestore, kMask };
inline constexpr const char* kFilterMasksDir = "masks";          // restore mode: <out>/masks/<view>.png
inline constexpr const char* kFilterReportFile = "filter.json";  // written last: the output is complete
const char* to_string(FilterMode m);

struct FilterDatasetOptions {
  ImageKind input = ImageKind::kImages;  // which images to filter (kImages or kClean)
  FilterMode mode = FilterMode::kRestore;
  ParticleFilterOptions filter;
};

struct FilterViewReport {
  std::string view;
  double mask_fraction = 0;
};
struct FilterDatasetReport {
  std::vector<FilterViewReport> views;  // dataset order
  double seconds = 0;
};

// Every view of the dataset, in parallel; `out` is written atomically with filter.json (method,
// parameters, per-view mask fraction, seconds). InputError names the dataset, view or option.
FilterDatasetReport filter_dataset(const std::string& dataset, const std::string& out, const FilterDatasetOptions& options);

}  // namespace weathergs::restoration
