#include "capture/import.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/dataset_identity.h"
#include "core/progress.h"
#include "core/error.h"
#include "capture/exports.h"

namespace weathergs::capture {

namespace fs = std::filesystem;

void ImportOptions::validate() const {
  if (video.empty() == images_dir.empty()) throw InputError("import options", "give exactly one of video (a file) and images_dir (a folder)");
  if (!video.empty() && !fs::is_regular_file(video)) throw InputError(video, "video file not found");
  if (!images_dir.empty() && !fs::is_directory(images_dir)) throw InputError(images_dir, "image folder not found");
  if (every < 1) throw InputError("import options", "every must be an integer >= 1, got " + std::to_string(every));
  if (max_frames < 3) throw InputError("import options", "max_frames must be an integer >= 3, got " + std::to_string(max_frames));
  if (max_size_px != 0 && max_size_px < 64)
    throw InputError("import options", "max_size_px must be 0 (keep) or at least 64 pixels, got " + std::to_string(max_size_px));
  if (!name.empty() && !is_safe_view_name(name)) throw InputError("import options", "name \"" + name + "\" must be made of [A-Za-z0-9._-]");
}

namespace {

cv::Mat limit_size(const cv::Mat& img, int max_size) {
  const int long_side = std::max(img.cols, img.rows);
  if (max_size <= 0 || long_side <= max_size) return img;
  const double s = double(max_size) / long_side;
  cv::Mat out;
  cv::resize(img, out, cv::Size(int(std::lround(img.cols * s)), int(std::lround(img.rows * s))), 0, 0, cv::INTER_AREA);
  return out;
}

struct Keyframe {
  std::string name;
  double time_s = 0;
  std::string origin;  // "frame 120" or the source file name
};

}  // namespace

ImportSummary import_footage(const ImportOptions& o, const std::string& out_dir) {
  o.validate();
  ImportSummary summary;
  const auto t0 = std::chrono::steady_clock::now();
  AtomicDirectory out(out_dir);
  const fs::path root(out.path());
  const fs::path frames = root / "logs" / "frames";
  fs::create_directories(frames);
  std::vector<Keyframe> keys;
  cv::Size size;
  auto save = [&](const cv::Mat& bgr, double time_s, const std::string& origin) {
    const cv::Mat img = limit_size(bgr, o.max_size_px);
    if (keys.empty()) size = img.size();
    if (img.size() != size)
      throw InputError(origin, "all frames must have one size (" + std::to_string(size.width) + "x" +
                                   std::to_string(size.height) + "), got " + std::to_string(img.cols) + "x" +
                                   std::to_string(img.rows));
    Keyframe k{numbered_view_name(int(keys.size()), 5), time_s, origin};
    if (!cv::imwrite((frames / (k.name + ".png")).string(), img))
      throw InputError((frames / (k.name + ".png")).string(), "cannot write keyframe");
    keys.push_back(k);
  };
  Json source;
  if (!o.video.empty()) {
    cv::VideoCapture cap(o.video);
    if (!cap.isOpened()) throw InputError(o.video, "OpenCV cannot open this video (unsupported codec or not a video)");
    const double fps = cap.get(cv::CAP_PROP_FPS);
    cv::Mat frame;
    for (int index = 0; int(keys.size()) < o.max_frames && cap.read(frame); ++index) {
      if (index % o.every != 0) continue;
      if (frame.empty()) continue;
      save(frame, fps > 0 ? index / fps : 0.0, o.video + " frame " + std::to_string(index));
    }
    source = {{"video", fs::absolute(o.video).string()}, {"every", o.every}, {"fps", fps}};
  } else {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(o.images_dir)) {
      std::string ext = e.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
      if (e.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tif" || ext == ".tiff"))
        files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    for (const auto& f : files) {
      if (int(keys.size()) >= o.max_frames) break;
      const cv::Mat img = cv::imread(f.string(), cv::IMREAD_COLOR);
      if (img.empty()) throw InputError(f.string(), "cannot decode image");
      save(img, 0.0, f.filename().string());
    }
    source = {{"images", fs::absolute(o.images_dir).string()}};
  }
  if (keys.size() < 3)
    throw InputError(o.video.empty() ? o.images_dir : o.video,
                     "need at least 3 keyframes, got " + std::to_string(keys.size()) + " (take every fewer frames)");
  summary.frames = int(keys.size());
  summary.extract_s = seconds_since(t0);

  const auto t1 = std::chrono::steady_clock::now();
  Dataset ds;
  ds.root = root.string();
  MapperResult mapped = map_unknown_poses(frames.string(), ds.file(std::string(layout::kLogsDir) + "/colmap"),
                                          ds.file(layout::kSparseModelDir), o.colmap);
  summary.colmap_s = seconds_since(t1);
  summary.stats = mapped.stats;
  summary.registered = int(mapped.cameras.size());
  if (summary.registered < 3)
    throw InputError(o.video.empty() ? o.images_dir : o.video,
                     "COLMAP registered only " + std::to_string(summary.registered) + " of " +
                         std::to_string(summary.frames) + " keyframes");

  std::map<std::string, Keyframe> by_name;
  for (const auto& k : keys) by_name[k.name] = k;
  fs::create_directories(ds.dir(ImageKind::kImages));
  std::vector<std::string> names;
  for (Camera& c : mapped.cameras) {
    const Keyframe& k = by_name.at(c.name);
    c.time_s = k.time_s;
    c.exposure_s = 0;  // unknown for real footage
    fs::rename(frames / (c.name + layout::kImageExt), ds.path(ImageKind::kImages, c.name));
    names.push_back(c.name);
  }
  Json unregistered = Json::array();
  for (const auto& n : mapped.unregistered) unregistered.push_back({{"view", n}, {"from", by_name.at(n).origin}});
  fs::remove_all(frames);

  ds.cameras = mapped.cameras;
  ds.info.name = o.name.empty() ? fs::path(out.final_path()).filename().string() : o.name;
  ds.info.scene = ds.info.name;
  ds.info.weather = o.weather;
  ds.info.splits = llff_splits(names);
  ds.info.splits_rule = std::string(kLlffSplitRule);
  source["keyframes"] = summary.frames;
  source["registered"] = summary.registered;
  source["unregistered"] = unregistered;
  source["colmap"] = {{"points", mapped.stats.points},
                      {"mean_reprojection_error_px", mapped.stats.mean_reprojection_error_px}};
  ds.info.source = source;
  write_dataset(ds);
  write_transforms_json(ds.file(layout::kTransformsJson), ds.cameras);
  record_dataset_identity(root.string());
  out.commit();
  return summary;
}

}  // namespace weathergs::capture
