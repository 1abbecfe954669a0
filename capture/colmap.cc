#include "capture/colmap.h"

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

#include "core/atomic_file.h"
#include "core/colmap_model.h"
#include "core/dataset.h"
#include "core/dataset_identity.h"
#include "core/dataset_layout.h"
#include "core/error.h"
#include "capture/colmap_database.h"
#include "capture/process.h"
#include "capture/sift_matcher.h"

namespace weathergs::capture {

namespace fs = std::filesystem;

namespace {

void run_colmap(const ColmapOptions& o, const std::string& command, std::vector<std::string> args,
                const std::string& log_path) {
  std::vector<std::string> argv = {o.executable, command};
  argv.insert(argv.end(), args.begin(), args.end());
  ProcessOptions popts;
  popts.log_path = log_path;
  popts.timeout_s = o.timeout_s;
  const ProcessResult r = run_process(argv, "colmap " + command, popts);
  if (r.exit_code != 0)
    throw InputError("colmap " + command, "failed with exit code " + std::to_string(r.exit_code) +
                                              "; last lines of " + log_path + ":\n" + tail_of_file(log_path));
}

std::string threads(const ColmapOptions& o) { return std::to_string(o.num_threads); }

// SIFT extraction. On one thread COLMAP's extraction repeats (same keypoints, descriptors and
// image ids in list order), which the benchmark's known-pose models need; with more threads the ids
// follow completion order.
void extract(const ColmapOptions& o, const std::string& db, const std::string& image_dir, const std::string& list_path,
             const std::vector<std::string>& camera_args, const std::string& num_threads, const std::string& log) {
  std::vector<std::string> fe = {"--database_path", db, "--image_path", image_dir, "--image_list_path", list_path,
                                 "--ImageReader.camera_model", "PINHOLE", "--ImageReader.single_camera", "1",
                                 "--SiftExtraction.use_gpu", "0", "--SiftExtraction.num_threads", num_threads};
  fe.insert(fe.end(), camera_args.begin(), camera_args.end());
  run_colmap(o, "feature_extractor", fe, log);
}

// Footage of unknown poses keeps COLMAP's own matchers (the mapper is not deterministic anyway).
void extract_and_match(const ColmapOptions& o, const std::string& db, const std::string& image_dir,
                       const std::string& list_path, bool sequential, const std::string& log) {
  extract(o, db, image_dir, list_path, {}, threads(o), log);
  run_colmap(o, sequential ? "sequential_matcher" : "exhaustive_matcher",
             {"--database_path", db, "--SiftMatching.use_gpu", "0", "--SiftMatching.num_threads", threads(o)}, log);
}

// Exhaustive matching that repeats bit for bit (capture/sift_matcher.h), then COLMAP's geometric
// verification of those matches (matches_importer, repeatable with any thread count).
void match_exhaustive_deterministic(const ColmapOptions& o, const std::string& db, const std::string& work_dir,
                                    const std::string& log) {
  const std::string list = (fs::path(work_dir) / "matches.txt").string();
  write_exhaustive_match_list(db, list, SiftMatchOptions{});
  run_colmap(o, "matches_importer",
             {"--database_path", db, "--match_list_path", list, "--match_type", "raw", "--SiftMatching.use_gpu", "0",
              "--SiftMatching.num_threads", threads(o)},
             log);
}

struct DbImage {
  int image_id = 0, camera_id = 0;
};

// IMAGE_IDs come from the database: they are not in name order in general.
std::map<std::string, DbImage> read_image_ids(const std::string& db) {
  std::map<std::string, DbImage> ids;
  ColmapDatabase(db).query("SELECT image_id, camera_id, name FROM images;", [&](sqlite3_stmt* st) {
    const unsigned char* name = sqlite3_column_text(st, 2);
    if (!name) throw InputError(db, "an image row without a name");
    ids[reinterpret_cast<const char*>(name)] = {sqlite3_column_int(st, 0), sqlite3_column_int(st, 1)};
  });
  return ids;
}

int64_t count_verified_matches(const std::string& db) {
  int64_t n = 0;
  ColmapDatabase(db).query("SELECT COALESCE(SUM(rows), 0) FROM two_view_geometries;",
                     [&](sqlite3_stmt* st) { n = sqlite3_column_int64(st, 0); });
  return n;
}

// The image of a dataset view in image_dir; views are PNG.
std::string image_name(const Camera& c) { return c.name + ".png"; }

}  // namespace

void ColmapOptions::validate() const {
  const std::string where = "colmap options";
  if (executable.empty()) throw InputError(where, "executable is empty");
  if (num_threads != -1 && num_threads < 1)
    throw InputError(where, "num_threads is " + std::to_string(num_threads) + ", must be -1 (all cores) or >= 1");
  if (!(timeout_s >= 0)) throw InputError(where, "timeout_s is " + std::to_string(timeout_s) + ", must be >= 0");
}

ModelStats analyze_model(const std::string& model_dir, const ColmapOptions& o, const std::string& log_path) {
  // model_analyzer prints through glog; capture to its own file and parse the "Key: value" lines.
  const std::string out = log_path + ".analyzer.txt";
  fs::remove(out);
  ProcessOptions popts;
  popts.log_path = out;
  popts.timeout_s = o.timeout_s;
  const ProcessResult r = run_process({o.executable, "model_analyzer", "--path", model_dir}, "colmap model_analyzer", popts);
  const std::string text = read_file(out);
  {
    std::ofstream log(log_path, std::ios::app);
    log << text;
  }
  if (r.exit_code != 0)
    throw InputError(model_dir, "colmap model_analyzer cannot read the model:\n" + tail_of_file(out));
  ModelStats s;
  auto number = [&](const std::string& key, bool required) -> double {
    std::smatch m;
    const std::regex re("(?:^|[\\]\\s])" + key + ":\\s*([-+0-9.eE]+)");
    if (std::regex_search(text, m, re)) return std::stod(m[1].str());
    if (required) throw InputError(model_dir, "model_analyzer printed no \"" + key + ":\" line:\n" + tail_of_file(out));
    return 0;
  };
  s.cameras = int(number("Cameras", true));
  s.images = int(number("Images", true));
  s.registered_images = int(number("Registered images", true));
  s.points = int(number("Points", true));
  s.observations = int(number("Observations", false));
  s.mean_track_length = number("Mean track length", false);
  s.mean_reprojection_error_px = number("Mean reprojection error", true);
  return s;
}

TriangulationResult triangulate_known_poses(const std::vector<Camera>& cameras, const std::string& image_dir,
                                            const std::string& work_dir, const std::string& model_dir,
                                            const ColmapOptions& o) {
  WGS_CHECK(!cameras.empty());
  const Camera& c0 = cameras.front();
  for (const Camera& c : cameras)
    if (c.width != c0.width || c.height != c0.height || c.fx != c0.fx || c.fy != c0.fy || c.cx != c0.cx || c.cy != c0.cy)
      throw InputError(c.name, "known-pose triangulation needs one shared camera; view " + c.name +
                                   " has other intrinsics than " + c0.name);
  const auto start = std::chrono::steady_clock::now();
  fs::create_directories(work_dir);
  const std::string log = (fs::path(work_dir) / "colmap.log").string();
  const std::string db = (fs::path(work_dir) / "database.db").string();
  fs::remove(db);
  std::string list;
  for (const Camera& c : cameras) list += image_name(c) + "\n";
  const std::string list_path = (fs::path(work_dir) / "image_list.txt").string();
  write_file_atomic(list_path, list);
  std::ostringstream params;
  params.precision(17);
  params << c0.fx << "," << c0.fy << "," << c0.cx << "," << c0.cy;
  extract(o, db, image_dir, list_path, {"--ImageReader.camera_params", params.str()}, "1", log);
  match_exhaustive_deterministic(o, db, work_dir, log);

  const std::map<std::string, DbImage> ids = read_image_ids(db);
  // point_triangulator aborts in bundle adjustment when nothing can be triangulated: say why instead.
  if (count_verified_matches(db) == 0)
    throw InputError(image_dir, "COLMAP found no verified feature matches between the " +
                                    std::to_string(cameras.size()) +
                                    " views (images too small, too few views, or textureless); cannot triangulate");
  ColmapModel input;
  std::map<int, bool> camera_ids;
  for (const Camera& c : cameras) {
    auto it = ids.find(image_name(c));
    if (it == ids.end()) throw InputError(db, "COLMAP's database has no image " + image_name(c));
    ColmapImage img;
    img.id = it->second.image_id;
    img.camera_id = it->second.camera_id;
    img.name = image_name(c);
    img.camera_from_world = c.camera_from_world;
    input.images.push_back(img);
    if (!camera_ids.count(img.camera_id)) {
      camera_ids[img.camera_id] = true;
      input.cameras.push_back({img.camera_id, c.width, c.height, c.fx, c.fy, c.cx, c.cy});
    }
  }
  const fs::path in_dir = fs::path(work_dir) / "known_poses";
  const fs::path tri_dir = fs::path(work_dir) / "triangulated";
  fs::create_directories(in_dir);
  fs::create_directories(tri_dir);
  write_colmap_text(in_dir.string(), input);
  bool no_points = false;
  try {
    run_colmap(o, "point_triangulator",
             {"--database_path", db, "--image_path", image_dir, "--input_path", in_dir.string(), "--output_path",
              tri_dir.string(), "--Mapper.ba_refine_focal_length", "0", "--Mapper.ba_refine_principal_point", "0",
              "--Mapper.ba_refine_extra_params", "0",
              // The poses are exact, so true correspondences reproject within a pixel or two; matches on
              // lens drops and streaks do not. COLMAP's 4 px defaults let them into the model.
              "--Mapper.filter_max_reproj_error", "2", "--Mapper.tri_merge_max_reproj_error", "2",
              "--Mapper.tri_complete_max_reproj_error", "2", "--Mapper.num_threads", threads(o)},
             log);
  } catch (const InputError&) {
    // COLMAP 3.8's point_triangulator ends with a bundle adjustment whose solver CHECK-fails (abort,
    // exit 134) when no point was triangulated: few, small or weather-covered views (tiny pool_snow,
    // 5 views of 192x128). That is an empty result, not a failure: keep the known poses, no points.
    if (read_file(log).find("bundle_adjuster.Solve") == std::string::npos) throw;
    no_points = true;
  }
  fs::create_directories(model_dir);
  if (no_points)
    write_colmap_text(model_dir, input);
  else
    run_colmap(o, "model_converter",
               {"--input_path", tri_dir.string(), "--output_path", model_dir, "--output_type", "TXT"}, log);
  TriangulationResult result;
  result.no_points = no_points;
  result.stats = analyze_model(model_dir, o, log);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

MapperResult map_unknown_poses(const std::string& image_dir, const std::string& work_dir, const std::string& model_dir,
                               const ColmapOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  fs::create_directories(work_dir);
  const std::string log = (fs::path(work_dir) / "colmap.log").string();
  const std::string db = (fs::path(work_dir) / "database.db").string();
  fs::remove(db);
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(image_dir))
    if (e.is_regular_file()) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  if (names.size() < 3) throw InputError(image_dir, "need at least 3 images to map, found " + std::to_string(names.size()));
  std::string list;
  for (const auto& n : names) list += n + "\n";
  const std::string list_path = (fs::path(work_dir) / "image_list.txt").string();
  write_file_atomic(list_path, list);
  // Exhaustive matching up to 150 frames (a few minutes on 2 cores); sequential beyond (video order).
  extract_and_match(o, db, image_dir, list_path, names.size() > 150, log);
  const fs::path sparse = fs::path(work_dir) / "sparse";
  fs::create_directories(sparse);
  // Robust settings for sparse wide-baseline views (ENVIRONMENT.md).
  run_colmap(o, "mapper",
             {"--database_path", db, "--image_path", image_dir, "--output_path", sparse.string(),
              "--Mapper.init_min_num_inliers", "30", "--Mapper.abs_pose_min_num_inliers", "12",
              "--Mapper.abs_pose_min_inlier_ratio", "0.1", "--Mapper.min_model_size", "3", "--Mapper.num_threads",
              threads(o)},
             log);
  // The mapper may split the footage into several models: keep the one with most registered images.
  std::string best;
  int best_images = -1;
  for (const auto& e : fs::directory_iterator(sparse)) {
    if (!e.is_directory()) continue;
    ModelStats s = analyze_model(e.path().string(), o, log);
    if (s.registered_images > best_images) best_images = s.registered_images, best = e.path().string();
  }
  if (best.empty())
    throw InputError(image_dir, "COLMAP's mapper registered no model (too few overlapping frames? try a smaller --every)");
  fs::create_directories(model_dir);
  run_colmap(o, "model_converter", {"--input_path", best, "--output_path", model_dir, "--output_type", "TXT"}, log);
  MapperResult result;
  result.stats = analyze_model(model_dir, o, log);
  const ColmapModel model = read_colmap_text(model_dir);
  std::map<int, ColmapCameraModel> cams;
  for (const auto& c : model.cameras) cams[c.id] = c;
  std::map<std::string, Camera> by_name;
  for (const ColmapImage& img : model.images) {
    auto it = cams.find(img.camera_id);
    if (it == cams.end()) throw InputError(model_dir, "image " + img.name + " refers to a missing camera");
    Camera c;
    c.name = fs::path(img.name).stem().string();
    c.width = it->second.width;
    c.height = it->second.height;
    c.fx = it->second.fx;
    c.fy = it->second.fy;
    c.cx = it->second.cx;
    c.cy = it->second.cy;
    c.camera_from_world = img.camera_from_world;
    by_name[c.name] = c;
  }
  for (const auto& n : names) {
    const std::string stem = fs::path(n).stem().string();
    if (!by_name.count(stem)) result.unregistered.push_back(stem);
  }
  for (auto& [n, c] : by_name) result.cameras.push_back(c);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

const char* to_string(TriangulateImages i) { return i == TriangulateImages::kClean ? "clean" : "images"; }
const char* to_string(TriangulateViews v) { return v == TriangulateViews::kTrain ? "train" : "all"; }

bool has_sfm_points(const std::string& model_dir) {
  const fs::path p = fs::path(model_dir) / "points3D.txt";
  return fs::exists(p) && !read_colmap_points3d(p.string()).empty();
}

TriangulationResult triangulate_dataset(const std::string& dataset_dir, const TriangulateOptions& o,
                                        std::string* model_dir_out) {
  o.colmap.validate();
  const Dataset ds = read_dataset(dataset_dir);
  const bool clean = o.images == TriangulateImages::kClean;
  const std::string image_dir = ds.dir(clean ? ImageKind::kClean : ImageKind::kImages);
  if (!fs::is_directory(image_dir))
    throw InputError(image_dir, std::string("missing: the dataset has no ") + (clean ? "clean" : "input") + " images");
  std::vector<Camera> cameras;
  if (o.views == TriangulateViews::kAll) {
    cameras = ds.cameras;
  } else {
    for (const std::string& v : ds.split("train")) cameras.push_back(ds.camera(v));
  }
  if (cameras.size() < 2)
    throw InputError(dataset_dir, "triangulation needs at least 2 views, the dataset's " +
                                      std::string(to_string(o.views)) + " views are " + std::to_string(cameras.size()));
  for (const Camera& c : cameras) {
    const std::string img = (fs::path(image_dir) / image_name(c)).string();
    if (!fs::exists(img)) throw InputError(img, "missing: view " + c.name + " has no image");
  }
  const std::string model =
      !o.model_dir.empty() ? o.model_dir : ds.file(clean ? layout::kSparseCleanModelDir : layout::kSparseModelDir);
  if (fs::exists(model) && !o.force)
    throw InputError(model, "already holds a model: pass --force to replace it");
  const std::string logs = !o.logs_dir.empty() ? o.logs_dir
                                               : ds.file(std::string(layout::kLogsDir) + (clean ? "/colmap_clean" : "/colmap"));
  fs::create_directories(fs::path(model).parent_path());
  AtomicDirectory out(model);
  TriangulationResult r = triangulate_known_poses(cameras, image_dir, logs, out.path(), o.colmap);
  out.commit();
  // The dataset's own model changed: so did its identity (a model written elsewhere leaves it alone).
  if (o.model_dir.empty()) record_dataset_identity(dataset_dir);
  if (model_dir_out) *model_dir_out = model;
  return r;
}

}  // namespace weathergs::capture
