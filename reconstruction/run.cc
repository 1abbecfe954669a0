#include "reconstruction/run.h"

#include "reconstruction/init_random.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <limits>

#include "core/atomic_file.h"
#include "core/colmap_model.h"
#include "core/error.h"
#include "core/json_reader.h"
#include "core/image.h"
#include "core/progress.h"
#include "reconstruction/init_random.h"

namespace weathergs::reconstruction {

namespace fs = std::filesystem;

namespace {

constexpr const char* kRunFormat = "weathergs-3dgs-run";
// 2: images/masks as named choices plus images_dir/masks_dir (1 mixed folder paths into the names).
constexpr int kRunVersion = 2;

// What run.json records (a run folder's settings record and state).
struct RunRecord {
  bool complete = false;
  std::string dataset;
  TrainInputs inputs;
  std::string initialization;
  int iterations = 0, sh_degree = 0;
  int64_t num_gaussians = 0, num_distractors = 0;
  double train_seconds = 0, peak_rss_mb = 0, extent = 0;
  // CPU seconds of the training (every thread's); unset when it resumed from a checkpoint without them.
  std::optional<double> train_cpu_seconds;
  int densify_capped = 0;
  TrainOptions options;
  TrainOptions effective;  // written as effective_schedule for readers; derived from options, so not read
};

constexpr auto kRunFields = [](auto& s, auto& f) {
  using json_fields::Optional;
  f("complete", s.complete);
  f("dataset", s.dataset);
  kTrainInputsFields(s.inputs, f);
  f("initialization", s.initialization);
  f("iterations", s.iterations);
  f("sh_degree", s.sh_degree, json_fields::Bounds{0, kMaxShDegree});
  f("num_gaussians", s.num_gaussians);
  f("num_distractors", s.num_distractors, Optional{});  // desplat's; absent in older run.json
  f("train_seconds", s.train_seconds);
  f("train_cpu_seconds", s.train_cpu_seconds);  // left out while unknown
  f("peak_rss_mb", s.peak_rss_mb);
  f("densify_capped", s.densify_capped, Optional{});
  f("extent", s.extent);
  f.custom(
      "options", [&] { return s.options.to_json(); },
      [&](const JsonReader& r, const std::string& k) { s.options = TrainOptions::from_json(r.child(k)); });
  f.custom(
      "effective_schedule",
      [&] {
        const TrainOptions& e = s.effective;
        return Json{{"densify_from", e.densify_from},
                    {"densify_until", e.densify_until},
                    {"densification_interval", e.densification_interval},
                    {"opacity_reset_interval", e.opacity_reset_interval},
                    {"large_prune_from", e.large_prune_from},
                    {"sh_degree_interval", e.sh_degree_interval}};
      },
      [&](const JsonReader& r, const std::string& k) { r.mark(k); });
};

Json run_json(const TrainRunOptions& o, const Trainer& t, double seconds, std::optional<double> cpu_seconds,
              bool complete, const std::string& init) {
  RunRecord rec;
  rec.complete = complete;
  rec.dataset = fs::absolute(o.dataset).lexically_normal().string();
  rec.inputs = o.inputs;
  if (!o.inputs.points_dir.empty()) rec.inputs.points_dir = fs::absolute(o.inputs.points_dir).lexically_normal().string();
  rec.initialization = init;
  rec.iterations = t.iteration();
  rec.sh_degree = t.sh_degree();
  rec.num_gaussians = int64_t(t.gaussians().size()) - t.num_distractors();
  rec.num_distractors = t.num_distractors();
  rec.train_seconds = seconds;
  rec.train_cpu_seconds = cpu_seconds;
  rec.peak_rss_mb = peak_rss_mb();
  rec.densify_capped = t.densify_capped();
  rec.extent = t.extent();
  rec.options = t.options();
  rec.effective = t.effective_options();
  Json j = json_fields::write(rec, kRunFields);
  j["format"] = kRunFormat;
  j["version"] = kRunVersion;
  return j;
}

RunRecord read_run_json(const std::string& run_dir) {
  const std::string path = (fs::path(run_dir) / "run.json").string();
  if (!fs::exists(path)) throw InputError(path, "missing: not a training run folder");
  JsonReader r = JsonReader::from_file(path);
  if (r.get<std::string>("format") != kRunFormat) throw InputError(r.where("format"), std::string("expected ") + kRunFormat);
  if (const int v = r.get<int>("version"); v != kRunVersion)
    throw InputError(r.where("version"), "run folder of version " + std::to_string(v) + ", this weathergs reads version " +
                                             std::to_string(kRunVersion) + ": train it again");
  return json_fields::read(r, RunRecord{}, kRunFields, json_fields::Absent::kError);
}

}  // namespace

void TrainRunOptions::validate() const {
  if (dataset.empty()) throw InputError("train run options", "dataset is empty: the dataset folder is required");
  if (out.empty()) throw InputError("train run options", "out is empty: the run folder is required");
  for (int it : snapshot_at)
    if (it < 1) throw InputError("train run options", "snapshot_at holds " + std::to_string(it) + ": iterations must be >= 1");
  if (checkpoint_every < 0)
    throw InputError("train run options", "checkpoint_every is " + std::to_string(checkpoint_every) + ", must be >= 0");
  inputs.validate("train run options");
  train.validate("train options");
}

void RenderRunOptions::validate() const {
  for (const auto& [field, value] : {std::pair<const char*, const std::string*>{"model", &model}, {"out", &out},
                                     {"split", &split}, {"method", &method}})
    if (value->empty()) throw InputError("render options", std::string(field) + " is empty: it is required");
  if (!(depth_min_opacity > 0 && depth_min_opacity <= 1))
    throw InputError("render options",
                     "depth_min_opacity is " + std::to_string(depth_min_opacity) + ", must be in (0, 1]");
  if (snapshot < 0) throw InputError("render options", "snapshot is " + std::to_string(snapshot) + ", must be >= 0");
}

std::vector<float> render_depth(const GaussianSet<float>& g, const Camera& camera, double min_opacity) {
  // Two colour passes of the same rasterizer on a black background: colour = camera z of each
  // Gaussian (SH degree 0) gives sum(w_i z_i); colour = 1 gives sum(w_i).
  const RasterCamera<float> rc = RasterCamera<float>::from(camera);
  GaussianSet<float> z_model = g, one_model = g;
  const size_t n = g.size();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p(g.position[3 * i], g.position[3 * i + 1], g.position[3 * i + 2]);
    const double z = camera.to_camera(p).z();
    for (int c = 0; c < 3; ++c) {
      z_model.sh[i * 48 + size_t(c)] = float(rgb_to_sh0(std::max(z, 0.0)));
      one_model.sh[i * 48 + size_t(c)] = float(rgb_to_sh0(1.0));
    }
  }
  RasterSettings<float> rs;
  rs.sh_degree = 0;
  rs.outputs = RasterOutputs::kImage;
  RasterState<float> state;
  rasterize_forward(z_model, rc, rs, &state);
  const std::vector<float> weighted = state.image;
  rasterize_forward(one_model, rc, rs, &state);
  std::vector<float> depth(size_t(camera.width) * size_t(camera.height));
  for (size_t p = 0; p < depth.size(); ++p) {
    const float w = state.image[3 * p];
    depth[p] = w >= float(min_opacity) ? weighted[3 * p] / w : std::numeric_limits<float>::infinity();
  }
  return depth;
}

namespace {

// The SfM points a run starts from: those of inputs.points_dir (which must hold a model), else of the
// dataset's sparse/0; empty when there are none.
std::vector<ColmapPoint3D> initial_points(const Dataset& dataset, const TrainInputs& inputs) {
  const bool given = !inputs.points_dir.empty();
  const std::string path =
      (fs::path(given ? inputs.points_dir : dataset.file(layout::kSparseModelDir)) / "points3D.txt").string();
  if (given && !fs::exists(path)) throw InputError(path, "missing: points_dir must hold a COLMAP text model");
  return fs::exists(path) ? read_colmap_points3d(path) : std::vector<ColmapPoint3D>{};
}

}  // namespace

bool starts_from_points(const Dataset& dataset, const TrainInputs& inputs) {
  return !initial_points(dataset, inputs).empty();
}

GaussianSet<float> initial_gaussians(const Dataset& dataset, const TrainInputs& inputs, const TrainOptions& options,
                                     const std::vector<TrainView>& train_views, std::string* source) {
  const std::vector<ColmapPoint3D> pts = initial_points(dataset, inputs);
  if (!pts.empty()) {
    std::vector<Eigen::Vector3d> xyz, rgb;
    for (const ColmapPoint3D& p : pts) {
      xyz.push_back(p.xyz);
      rgb.push_back(p.rgb / 255.0);
    }
    *source = "colmap:" + std::to_string(pts.size());
    return init_from_points(xyz, rgb);
  }
  *source = "random:" + std::to_string(options.random_init_count);
  return init_random(train_views, options);
}

TrainOptions run_length_for(const TrainOptions& train, const Dataset& dataset) {
  const std::vector<std::string>& names = dataset.split("train");
  if (names.empty()) throw InputError(dataset.root, "has no training views");
  std::vector<Camera> cameras;
  for (const std::string& n : names) cameras.push_back(dataset.camera(n));
  return train.with_run_length(cameras);
}

StageOutput run_output(const std::string& run_dir, const TrainOptions& train) {
  StageOutput s;
  s.record = (fs::path(run_dir) / "run.json").string();
  if (!fs::exists(s.record)) return s;
  const Json j = read_json_file(s.record);
  if (std::string why = settings_mismatch(j.value("options", Json::object()), train.to_json()); !why.empty()) {
    s.state = StageOutput::State::kStale;
    s.why = "options." + why;
  } else if (j.value("complete", false)) {
    s.state = StageOutput::State::kComplete;
  } else if (fs::exists(fs::path(run_dir) / "checkpoint.bin")) {
    s.state = StageOutput::State::kPartial;
  }
  return s;
}

TrainRunResult train_run(const TrainRunOptions& given, const IterationCallback& on_iteration) {
  given.validate();
  const Dataset dataset = read_dataset(given.dataset);
  TrainRunOptions o = given;
  o.train = run_length_for(given.train, dataset);
  std::vector<TrainView> views = load_train_views(dataset, o.inputs);
  std::vector<Camera> cams;
  for (const TrainView& v : views) cams.push_back(v.camera);
  const double extent = scene_extent(cams);

  const fs::path run(o.out);
  const std::string ckpt = (run / "checkpoint.bin").string(), ply = (run / "point_cloud.ply").string(),
                    info = (run / "run.json").string();
  const bool has_run = fs::exists(ckpt) || fs::exists(info);
  if (has_run && !o.resume && !o.force)
    throw InputError(o.out, "already holds a training run: resume it or force a new one (train --resume / --force)");
  if (o.resume && !fs::exists(ckpt)) throw InputError(ckpt, "missing: nothing to resume");
  if (o.force && !o.resume)
    for (const std::string& f : {ckpt, ply, info}) fs::remove(f);
  fs::create_directories(run);

  std::string init;
  GaussianSet<float> initial = initial_gaussians(dataset, o.inputs, o.train, views, &init);
  Trainer trainer(std::move(views), std::move(initial), o.train, extent);
  double seconds_before = 0;
  std::optional<double> cpu_before = 0.0;
  if (o.resume) {
    const RunRecord ri = read_run_json(o.out);
    TrainInputs given = o.inputs;
    if (!given.points_dir.empty()) given.points_dir = fs::absolute(given.points_dir).lexically_normal().string();
    if (!(ri.inputs == given) || fs::path(ri.dataset) != fs::absolute(o.dataset).lexically_normal())
      throw InputError(info, "the run was trained on dataset " + ri.dataset + " with " + ri.inputs.to_string() +
                                 ": resume with the same inputs");
    seconds_before = trainer.load_checkpoint(ckpt, &cpu_before);
  }
  const auto t0 = std::chrono::steady_clock::now();
  const double cpu0 = process_cpu_seconds();
  double excluded = 0, excluded_cpu = 0;  // spent writing snapshots: not training
  auto elapsed = [&] { return seconds_before + seconds_since(t0) - excluded; };
  auto elapsed_cpu = [&]() -> std::optional<double> {
    if (!cpu_before) return std::nullopt;
    return *cpu_before + process_cpu_seconds() - cpu0 - excluded_cpu;
  };
  auto save = [&](bool complete) {
    const double s = elapsed();
    const std::optional<double> cpu = elapsed_cpu();
    trainer.save_checkpoint(ckpt, s, cpu);
    write_ply(ply, trainer.scene_gaussians());  // distractors (desplat) are never exported
    write_file_atomic(info, run_json(o, trainer, s, cpu, complete, init).dump(2) + "\n");
  };
  TrainRunResult result;
  while (trainer.iteration() < o.train.iterations) {
    const IterationStats st = trainer.step();
    result.final_loss = st.loss;
    result.final_psnr = st.psnr;
    if (on_iteration) on_iteration(st);
    if (st.iteration < o.train.iterations &&
        std::find(o.snapshot_at.begin(), o.snapshot_at.end(), st.iteration) != o.snapshot_at.end()) {
      const auto w0 = std::chrono::steady_clock::now();
      const double c0 = process_cpu_seconds();
      const double s = elapsed();
      const std::string stem = snapshot_stem(o.out, st.iteration);
      fs::create_directories(fs::path(stem).parent_path());
      write_ply(stem + ".ply", trainer.scene_gaussians());
      write_file_atomic(stem + ".json", Json{{"iteration", st.iteration},
                                             {"train_seconds", s},
                                             {"num_gaussians", int64_t(trainer.gaussians().size()) - trainer.num_distractors()}}
                                                .dump(2) + "\n");
      excluded += seconds_since(w0);
      excluded_cpu += process_cpu_seconds() - c0;
    }
    if (o.checkpoint_every > 0 && st.iteration % o.checkpoint_every == 0 && st.iteration < o.train.iterations)
      save(false);
  }
  save(true);
  result.iterations = trainer.iteration();
  result.num_gaussians = int64_t(trainer.gaussians().size()) - trainer.num_distractors();
  result.train_seconds = elapsed();
  result.train_cpu_seconds = elapsed_cpu();
  result.peak_rss_mb = peak_rss_mb();
  return result;
}

TrainRunOptions read_run_options(const std::string& run_dir) {
  const RunRecord ri = read_run_json(run_dir);
  TrainRunOptions o;
  o.dataset = ri.dataset;
  o.inputs = ri.inputs;
  o.out = run_dir;
  o.train = ri.options;
  return o;
}

std::string snapshot_stem(const std::string& run_dir, int iteration) {
  char name[32];
  std::snprintf(name, sizeof name, "iter_%06d", iteration);
  return (fs::path(run_dir) / "snapshots" / name).string();
}

RenderRunResult render_run(const RenderRunOptions& o) {
  o.validate();
  RunRecord ri = read_run_json(o.model);
  std::string ply = (fs::path(o.model) / "point_cloud.ply").string();
  if (o.snapshot > 0) {
    const std::string stem = snapshot_stem(o.model, o.snapshot);
    if (!fs::exists(stem + ".ply") || !fs::exists(stem + ".json"))
      throw InputError(stem + ".ply", "missing: the run kept no snapshot at iteration " + std::to_string(o.snapshot));
    JsonReader r = JsonReader::from_file(stem + ".json");
    ri.iterations = r.get<int>("iteration");
    ri.train_seconds = r.get<double>("train_seconds");
    ri.train_cpu_seconds.reset();  // snapshots record wall seconds only
    r.get<int64_t>("num_gaussians");
    r.finish();
    ply = stem + ".ply";
  }
  const GaussianSet<float> g = read_ply(ply);
  const Dataset dataset = read_dataset(o.dataset.empty() ? ri.dataset : o.dataset);
  // "all": every view of the dataset (e.g. depth for the weather generator).
  std::vector<std::string> all_views;
  for (const Camera& c : dataset.cameras) all_views.push_back(c.name);
  const std::vector<std::string>& names = o.split == "all" ? all_views : dataset.split(o.split);
  RasterSettings<float> rs;
  rs.sh_degree = ri.sh_degree;
  rs.outputs = RasterOutputs::kImage;
  for (int c = 0; c < 3; ++c) rs.background[c] = float(ri.options.background[c]);
  AtomicDirectory dir(o.out);
  RasterState<float> state;
  RenderRunResult result;
  for (const std::string& name : names) {
    const Camera& cam = dataset.camera(name);
    const auto t0 = std::chrono::steady_clock::now();
    rasterize_forward(g, RasterCamera<float>::from(cam), rs, &state);
    result.render_seconds += seconds_since(t0);
    Image img(cam.width, cam.height, 3);
    for (size_t i = 0; i < img.data.size(); ++i) img.data[i] = std::clamp(state.image[i], 0.f, 1.f);
    write_image((fs::path(dir.path()) / (name + layout::kImageExt)).string(), img);
    if (o.depth) {
      const fs::path depth_dir = fs::path(dir.path()) / layout::kDepthDir;
      fs::create_directories(depth_dir);
      Image d(cam.width, cam.height, 1, ColorSpace::kLinear);
      d.data = render_depth(g, cam, o.depth_min_opacity);
      write_depth((depth_dir / (name + layout::kDepthExt)).string(), d);
    }
    ++result.views;
  }
  Json info{{"method", o.method},
            {"train_seconds", ri.train_seconds},
            {"peak_rss_mb", std::max(ri.peak_rss_mb, peak_rss_mb())},
            {"num_gaussians", g.size()},
            {"iterations", ri.iterations},
            {"render_seconds", result.render_seconds}};
  if (ri.train_cpu_seconds) info["train_cpu_seconds"] = *ri.train_cpu_seconds;
  write_file_atomic((fs::path(dir.path()) / "info.json").string(), info.dump(2) + "\n");
  dir.commit();
  return result;
}

}  // namespace weathergs::reconstruction
