#include "restoration/filter_dataset.h"

#include <chrono>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/error.h"
#include "core/image.h"
#include "core/json_reader.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace weathergs::restoration {

namespace fs = std::filesystem;

const char* to_string(FilterMode m) { return m == FilterMode::kMask ? "mask" : "restore"; }

FilterDatasetReport filter_dataset(const std::string& dataset, const std::string& out, const FilterDatasetOptions& o) {
  o.filter.validate();
  if (o.input != ImageKind::kImages && o.input != ImageKind::kClean)
    throw InputError("filter options", "input must be the dataset's images or clean images");
  const auto start = std::chrono::steady_clock::now();
  const Dataset ds = read_dataset(dataset);
  const std::string in_dir = ds.dir(o.input);
  if (!fs::is_directory(in_dir)) throw InputError(in_dir, "missing: the dataset has no such images");
  // Every input must exist before anything is written.
  for (const Camera& c : ds.cameras)
    if (!fs::exists(ds.path(o.input, c.name))) throw InputError(ds.path(o.input, c.name), "missing: view " + c.name);
  AtomicDirectory dir(out);
  if (o.mode == FilterMode::kRestore) fs::create_directories(fs::path(dir.path()) / kFilterMasksDir);
  FilterDatasetReport report;
  report.views.resize(ds.cameras.size());
  parallel_for(0, int64_t(ds.cameras.size()), [&](int64_t i) {
    const Camera& c = ds.cameras[size_t(i)];
    const std::string path = ds.path(o.input, c.name);
    const Image img = read_image(path);
    if (img.width != c.width || img.height != c.height)
      throw InputError(path, "is " + img.to_string() + ", cameras.json says " + std::to_string(c.width) + "x" +
                                 std::to_string(c.height));
    const ParticleFilterResult r = filter_particles(img, o.filter, path);
    const std::string name = c.name + layout::kImageExt;
    if (o.mode == FilterMode::kRestore) {
      write_image((fs::path(dir.path()) / name).string(), r.restored);
      write_mask((fs::path(dir.path()) / kFilterMasksDir / name).string(), r.mask);
    } else {
      write_mask((fs::path(dir.path()) / name).string(), r.mask);
    }
    report.views[size_t(i)] = {c.name, r.mask_fraction};
  });
  report.seconds = seconds_since(start);
  Json views = Json::array();
  for (const FilterViewReport& v : report.views) views.push_back({{"view", v.view}, {"mask_fraction", v.mask_fraction}});
  const Json j{{"format", "weathergs-filter"},
               {"version", 1},
               {"method", "tophat"},
               {"dataset", fs::absolute(dataset).lexically_normal().string()},
               {"input", o.input == ImageKind::kClean ? "clean" : "images"},
               {"mode", to_string(o.mode)},
               {"parameters",
                {{"radius_px_at_300", o.filter.radius_px_at_300},
                 {"radius_px", ds.cameras.empty() ? 0 : o.filter.radius_px(ds.cameras.front().width)},
                 {"threshold", o.filter.threshold},
                 {"dilate_px", o.filter.dilate_px}}},
               {"seconds", report.seconds},
               {"views", views}};
  write_file_atomic((fs::path(dir.path()) / kFilterReportFile).string(), j.dump(2) + "\n");
  dir.commit();
  return report;
}

}  // namespace weathergs::restoration
