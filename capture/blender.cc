#include "capture/blender.h"

#include <cerrno>
#include <chrono>
#include <exception>
#include <thread>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/error.h"
#include "core/image.h"
#include "core/progress.h"
#include "capture/process.h"

namespace weathergs::capture {

namespace fs = std::filesystem;

namespace {

// The camera's clip range, sent to the script in the job: depth at or beyond the far clip is
// background, which the dataset stores as +inf (kBackgroundDepthM). EEVEE writes 65504 (half-float
// max) there, Cycles the clip distance; both are >= kClipEndM.
constexpr float kClipStartM = 0.05f, kClipEndM = 1000.0f;
// The script's output folders inside the job's output_dir (renamed into the dataset layout here).
constexpr const char* kRawImagesDir = "clean";
constexpr const char* kRawDepthDir = "depth_raw";
// Blender stores matrix_world in float32: poses read back differ from the requested ones by ~1e-6.
constexpr double kPoseTolerance = 1e-4;

Json matrix_json(const Eigen::Matrix4d& m) {
  Json rows = Json::array();
  for (int i = 0; i < 4; ++i) rows.push_back({m(i, 0), m(i, 1), m(i, 2), m(i, 3)});
  return rows;
}

void link_or_copy(const fs::path& from, const fs::path& to) {
  std::error_code ec;
  fs::create_hard_link(from, to, ec);
  if (ec) fs::copy_file(from, to, fs::copy_options::overwrite_existing);
}

// One Blender process of a render: a contiguous run of views, its own job, log and output folder.
struct RenderPart {
  int first_view = 0, end_view = 0;
  int threads = 0;  // Blender's -t
  fs::path job, log, out;
};

// Cycles renders the same pixels in every process only on one thread (with more, a pixel in ~25,000
// may differ by one level: Embree's threaded BVH build), so a Cycles render runs as one-thread
// processes side by side, one per available thread, each on its own views. EEVEE repeats under no
// setting (docs/scenes.md, "Repeatability") and runs as one process with every thread given.
std::vector<RenderPart> plan_render_parts(const std::string& engine, int views, int threads, const fs::path& root,
                                          const fs::path& raw) {
  int processes = 1;
  if (engine == "cycles") {
    const int available = threads > 0 ? threads : std::max(1, int(std::thread::hardware_concurrency()));
    processes = std::max(1, std::min(available, views));
  }
  std::vector<RenderPart> parts;
  for (int k = 0; k < processes; ++k) {
    RenderPart p;
    p.first_view = int(int64_t(views) * k / processes);
    p.end_view = int(int64_t(views) * (k + 1) / processes);
    p.threads = engine == "cycles" ? 1 : threads;
    const std::string suffix = processes == 1 ? "" : "_" + std::to_string(k);
    p.job = root / "logs" / ("blender_job" + suffix + ".json");
    p.log = root / "logs" / ("blender" + suffix + ".log");
    p.out = processes == 1 ? raw : raw / ("part_" + std::to_string(k));
    fs::create_directories(p.out);
    parts.push_back(p);
  }
  return parts;
}

}  // namespace

void BlenderOptions::validate() const {
  const std::string where = "blender options";
  if (executable.empty()) throw InputError(where, "executable is empty");
  if (script.empty()) throw InputError(where, "script is empty: the path of blender_scripts/render_scene.py is required");
  if (!(timeout_s >= 0)) throw InputError(where, "timeout_s is " + std::to_string(timeout_s) + ", must be >= 0");
  if (max_views < 0) throw InputError(where, "max_views is " + std::to_string(max_views) + ", must be >= 0");
  if (threads < 0) throw InputError(where, "threads is " + std::to_string(threads) + ", must be >= 0 (0 = all cores)");
}

Json blender_job(const SceneSpec& scene, const VariantSpec& variant, const ProfileSpec& profile,
                 const std::vector<Camera>& cameras, const std::vector<Marker>& markers) {
  Json views = Json::array();
  for (const Camera& c : cameras)
    views.push_back({{"name", c.name}, {"camera_from_world", matrix_json(c.camera_from_world)},
                     {"time_s", c.time_s}, {"exposure_s", c.exposure_s}});
  Json marker_list = Json::array();
  for (const Marker& m : markers)
    marker_list.push_back({{"p_world", {m.p_world.x(), m.p_world.y(), m.p_world.z()}}, {"radius_m", m.radius_m}});
  return {{"format", "weathergs-blender-job"},
          {"version", 1},
          {"scene_file", scene.file},
          {"scene", {{"name", scene.name}, {"type", scene.type}, {"seed", scene.seed},
                     {"layout", scene.layout}, {"materials", scene.materials}}},
          {"variant", variant.name},
          {"surface", variant.surface},
          {"lights", variant.lights},
          {"render", {{"engine", profile.engine}, {"width", profile.width}, {"height", profile.height},
                      {"samples", profile.samples}, {"seed", 0}}},
          {"camera", {{"focal_length_mm", scene.camera.focal_length_mm},
                      {"sensor_width_mm", scene.camera.sensor_width_mm},
                      {"clip_start_m", kClipStartM},
                      {"clip_end_m", kClipEndM},
                      {"views", views}}},
          {"outputs", {{"images", kRawImagesDir}, {"depth", kRawDepthDir}}},
          {"markers", marker_list}};
}

ProcessResult run_blender_job(const std::string& executable, const std::string& script, const std::string& job_path,
                              const std::string& what, const ProcessOptions& options, int threads) {
  WGS_CHECK_GE(threads, 0);
  // Blender keeps a session folder (blender_XXXXXX) in $TMPDIR and leaves it behind when the script
  // raises (--python-exit-code) or the run is killed: every failed render left one in /tmp. It gets a
  // TMPDIR of its own next to the job file instead (a unique name: two runs may share the folder),
  // removed when the run ends, however it ends.
  std::string pattern = (fs::absolute(fs::path(job_path)).parent_path() / "blender_tmp_XXXXXX").string();
  if (!::mkdtemp(pattern.data()))
    throw InputError(pattern, std::string("cannot create Blender's temporary folder: ") + std::strerror(errno));
  const fs::path tmp = pattern;
  struct RemoveOnExit {
    fs::path path;
    ~RemoveOnExit() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  } remove_tmp{tmp};
  ProcessOptions with_tmp = options;
  with_tmp.env.push_back("TMPDIR=" + tmp.string());
  std::vector<std::string> argv{executable, "-b", "--factory-startup"};
  if (threads > 0) {
    // -t must come before --python: Blender applies its arguments in order, and the script renders.
    argv.insert(argv.end(), {"-t", std::to_string(threads)});
    with_tmp.env.push_back("LP_NUM_THREADS=" + std::to_string(threads));  // EEVEE renders through llvmpipe
  }
  argv.insert(argv.end(), {"--python-exit-code", "1", "--python", script, "--", job_path});
  return run_process(argv, what, with_tmp);
}

RenderSummary render_clean_dataset(const SceneSpec& scene, const std::string& variant_name, const std::string& profile_name,
                                   const std::string& out_dir, const BlenderOptions& options,
                                   const std::vector<Marker>& markers) {
  const VariantSpec variant = scene.variant(variant_name);
  const ProfileSpec& profile = scene.profile(profile_name);
  std::vector<Camera> cameras = scene_cameras(scene, profile);
  if (options.max_views > 0 && int(cameras.size()) > options.max_views) cameras.resize(size_t(options.max_views));
  options.validate();
  if (!fs::is_regular_file(options.script)) throw InputError(options.script, "Blender script not found");

  AtomicDirectory dir(out_dir);
  const fs::path root(dir.path());
  const fs::path raw = root / "render";
  fs::create_directories(root / "logs");
  fs::create_directories(raw);
  const std::vector<RenderPart> parts = plan_render_parts(profile.engine, int(cameras.size()), options.threads, root, raw);
  Json job = blender_job(scene, variant, profile, cameras, markers);
  std::vector<std::thread> workers;
  std::vector<ProcessResult> results(parts.size());
  std::vector<std::exception_ptr> errors(parts.size());
  const auto start = std::chrono::steady_clock::now();
  for (size_t k = 0; k < parts.size(); ++k) {
    const RenderPart& part = parts[k];
    Json part_job = job;
    Json views = Json::array();
    for (int i = part.first_view; i < part.end_view; ++i) views.push_back(job["camera"]["views"][size_t(i)]);
    part_job["camera"]["views"] = views;
    part_job["output_dir"] = part.out.string();
    write_file_atomic(part.job.string(), part_job.dump(1));
    workers.emplace_back([&, k] {
      try {
        ProcessOptions popts;
        popts.log_path = parts[k].log.string();
        popts.timeout_s = options.timeout_s;
        results[k] = run_blender_job(options.executable, options.script, parts[k].job.string(),
                                     "blender (" + options.executable + ")", popts, parts[k].threads);
      } catch (...) {
        errors[k] = std::current_exception();
      }
    });
  }
  for (std::thread& t : workers) t.join();
  for (const std::exception_ptr& e : errors)
    if (e) std::rethrow_exception(e);
  const double render_seconds = seconds_since(start);
  for (size_t k = 0; k < parts.size(); ++k) {
    const fs::path error_file = parts[k].out / "error.json";
    if (fs::exists(error_file)) {
      // The script reports spec errors with their location in the scene file.
      Json err;
      try {
        err = Json::parse(read_file(error_file.string()));
      } catch (const Json::exception&) {
      }
      if (err.is_object() && err.contains("where") && err.contains("what"))
        throw InputError(err["where"].get<std::string>(), err["what"].get<std::string>());
    }
    if (results[k].exit_code != 0)
      throw InputError("blender (" + options.executable + ")",
                       "rendering " + scene.name + "/" + variant.name + " failed with exit code " +
                           std::to_string(results[k].exit_code) + "; last lines of its log (" + parts[k].log.string() +
                           "):\n" + tail_of_file(parts[k].log.string()));
  }

  // Blender's own account of the cameras it rendered with must match the path we asked for.
  std::vector<Camera> rendered;
  std::vector<fs::path> part_of_view;
  for (const RenderPart& part : parts) {
    const std::string rendered_cameras = (part.out / layout::kCamerasJson).string();
    const std::vector<Camera> got = read_cameras_json(rendered_cameras);
    if (int(got.size()) != part.end_view - part.first_view)
      throw InputError(rendered_cameras, "Blender wrote " + std::to_string(got.size()) + " cameras, expected " +
                                             std::to_string(part.end_view - part.first_view));
    for (const Camera& c : got) rendered.push_back(c), part_of_view.push_back(part.out);
  }
  const std::string rendered_cameras = (parts.front().out / layout::kCamerasJson).string();
  for (size_t i = 0; i < cameras.size(); ++i) {
    const Camera &a = cameras[i], &b = rendered[i];
    const double pose = (a.camera_from_world - b.camera_from_world).cwiseAbs().maxCoeff();
    const double intr = std::max({std::abs(a.fx - b.fx), std::abs(a.fy - b.fy), std::abs(a.cx - b.cx), std::abs(a.cy - b.cy)});
    if (a.name != b.name || a.width != b.width || a.height != b.height || pose > kPoseTolerance || intr > 1e-6 * a.fx)
      throw InputError(rendered_cameras,
                       "Blender's camera for view " + a.name + " differs from the requested one: requested " +
                           a.to_string() + ", rendered " + b.to_string());
  }

  Dataset ds;
  ds.root = root.string();
  for (ImageKind k : {ImageKind::kClean, ImageKind::kImages, ImageKind::kDepth}) fs::create_directories(ds.dir(k));
  std::vector<std::string> names;
  for (size_t i = 0; i < rendered.size(); ++i) {
    const Camera& cam = rendered[i];
    const fs::path png = part_of_view[i] / kRawImagesDir / (cam.name + layout::kImageExt);
    const Image img = read_image(png.string());
    if (img.width != cam.width || img.height != cam.height)
      throw InputError(png.string(), "expected " + std::to_string(cam.width) + "x" + std::to_string(cam.height) +
                                         ", got " + img.to_string());
    // Re-encoded rather than moved: Blender's PNGs carry the render's date and timings as metadata,
    // so two renders of identical pixels would be different files.
    write_image(ds.path(ImageKind::kClean, cam.name), img);
    link_or_copy(ds.path(ImageKind::kClean, cam.name), ds.path(ImageKind::kImages, cam.name));
    const std::string raw_depth = (part_of_view[i] / kRawDepthDir / (cam.name + layout::kDepthExt)).string();
    Image depth = read_depth(raw_depth);
    if (depth.width != cam.width || depth.height != cam.height)
      throw InputError(raw_depth, "depth size differs from the image");
    // Blender writes its far clip (or EEVEE's 65504) where there is no geometry: background.
    for (float& z : depth.data)
      if (!(z < kClipEndM)) z = std::numeric_limits<float>::infinity();
    write_depth(ds.path(ImageKind::kDepth, cam.name), depth);
    names.push_back(cam.name);
  }

  RenderSummary summary;
  summary.seconds = render_seconds;
  summary.views = int(rendered.size());
  summary.processes = int(parts.size());
  // One render log for the whole render: the parts' view timings in view order.
  Json log_all = {{"processes", parts.size()}, {"view_seconds", Json::array()}, {"parts", Json::array()}};
  for (const RenderPart& part : parts) {
    const JsonReader log = JsonReader::from_file((part.out / "render_log.json").string());
    summary.objects = log.get<int>("objects");
    for (const Json& t : log.value()["view_seconds"]) log_all["view_seconds"].push_back(t);
    log_all["parts"].push_back(log.value());
  }
  log_all["blender"] = log_all["parts"][0].value("blender", "");
  log_all["engine"] = log_all["parts"][0].value("engine", "");
  log_all["objects"] = summary.objects;
  if (!log_all["view_seconds"].empty()) summary.first_view_s = log_all["view_seconds"][0].get<double>();
  write_file_atomic((root / "logs" / "render_log.json").string(), log_all.dump(1));
  fs::remove_all(raw);

  // Lens data is ours, not Blender's (it renders a pinhole; the generator applies the lens): carry it over.
  for (size_t i = 0; i < rendered.size(); ++i) {
    rendered[i].focal_length_mm = cameras[i].focal_length_mm;
    rendered[i].f_number = cameras[i].f_number;
    rendered[i].focus_distance_m = cameras[i].focus_distance_m;
  }
  ds.cameras = rendered;
  ds.info.name = scene.name + "_" + variant.name + "_clean";
  ds.info.scene = scene.name;
  ds.info.weather = "clear";
  ds.info.splits = llff_splits(names, scene.split_every);
  ds.info.splits_rule = scene.split_every == 8 ? std::string(kLlffSplitRule)
                                               : "llff_every_" + std::to_string(scene.split_every);
  // The render's own entries of the generator block (later stages add theirs, docs/scenes.md).
  ds.info.generator = Json{{"stages", {{{"name", "blender"}, {"seconds", render_seconds}}}},
                           {"profile", profile.name},
                           {"variant", variant.name},
                           {"surface", variant.surface}};
  write_dataset(ds);
  dir.commit();
  return summary;
}

}  // namespace weathergs::capture
