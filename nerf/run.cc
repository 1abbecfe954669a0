#include "nerf/run.h"

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/colmap_model.h"
#include "core/dataset_layout.h"
#include "core/error.h"
#include "core/image.h"
#include "core/json_fields.h"
#include "core/json_reader.h"
#include "core/progress.h"

namespace weathergs::nerf {

namespace fs = std::filesystem;

namespace {

constexpr int kRunVersion = 1;
constexpr const char* kFieldFile = "field.bin";
constexpr const char* kRunJson = "run.json";
constexpr const char* kCheckpointFile = "checkpoint.bin";
constexpr double kMinNearM = 0.05;      // the generator's own near clip (capture: Cycles clip_start)
constexpr double kDefaultNearM = 1.0;   // without SfM points

// What a radiance-field run's run.json records.
struct RunRecord {
  bool complete = false;
  std::string dataset;
  TrainInputs inputs;
  int iterations = 0;
  double train_seconds = 0, peak_rss_mb = 0;
  std::optional<double> train_cpu_seconds;  // every thread's; absent from older records
  std::array<int, 3> lattice = {2, 2, 2};
  int64_t occupied_cells = 0;
  double near_m = 0;
  std::string near_source;
  FrustumFrame frame;
  NerfOptions options;
};

constexpr auto kRunFields = [](auto& s, auto& f) {
  f("complete", s.complete);
  f("dataset", s.dataset);
  kTrainInputsFields(s.inputs, f);
  f("iterations", s.iterations);
  f("train_seconds", s.train_seconds);
  f("train_cpu_seconds", s.train_cpu_seconds);
  f("peak_rss_mb", s.peak_rss_mb);
  f("lattice", s.lattice);
  f("occupied_cells", s.occupied_cells);
  f("near_m", s.near_m);
  f("near_source", s.near_source);
  f.custom(
      "frame", [&] { return s.frame.to_json(); },
      [&](const JsonReader& r, const std::string& k) { s.frame = FrustumFrame::from_json(r.child(k)); });
  f.custom(
      "options", [&] { return s.options.to_json(); },
      [&](const JsonReader& r, const std::string& k) { s.options = NerfOptions::from_json(r.child(k)); });
};

Json run_json(const RunRecord& rec) {
  Json j = json_fields::write(rec, kRunFields);
  j["format"] = kNerfRunFormat;
  j["version"] = kRunVersion;
  return j;
}

RunRecord read_run_info(const std::string& run_dir) {
  const std::string path = (fs::path(run_dir) / kRunJson).string();
  if (!fs::exists(path)) throw InputError(path, "missing: not a radiance-field run folder");
  const JsonReader r = JsonReader::from_file(path);
  if (r.get<std::string>("format") != kNerfRunFormat)
    throw InputError(r.where("format"), std::string("expected ") + kNerfRunFormat);
  if (r.get<int>("version") != kRunVersion) throw InputError(r.where("version"), "expected version " + std::to_string(kRunVersion));
  return json_fields::read(r, RunRecord{}, kRunFields, json_fields::Absent::kError);
}

// A folder as a record names it: absolute, normalised, without a trailing separator, so that one
// folder named two ways is the same data.
std::string record_dir(const std::string& dir) {
  fs::path p = fs::absolute(dir).lexically_normal();
  if (!p.has_filename() && p.has_parent_path()) p = p.parent_path();
  return p.string();
}

// The settings a run is judged by, as its record writes them: the data and every option, the seed
// included.
RunRecord settings_record(const std::string& dataset, const TrainInputs& inputs, const NerfOptions& options) {
  RunRecord rec;
  rec.dataset = record_dir(dataset);
  rec.inputs = inputs;
  for (std::string* dir : {&rec.inputs.images_dir, &rec.inputs.masks_dir, &rec.inputs.points_dir})
    if (!dir->empty()) *dir = record_dir(*dir);
  rec.options = options;
  return rec;
}

// Renders `names` of the dataset into an atomic folder with info.json.
NerfRenderResult render_views(const RadianceField& field, const Dataset& ds, const std::vector<std::string>& names,
                              const MarchSettings& march, const std::string& out, const Json& info_base) {
  fs::create_directories(fs::path(out).parent_path());
  AtomicDirectory dir(out);
  NerfRenderResult r;
  for (const std::string& name : names) {
    const Camera& cam = ds.camera(name);
    const auto t0 = std::chrono::steady_clock::now();
    Image img(cam.width, cam.height, 3);
    img.data = field.render(cam, march);
    r.render_seconds += seconds_since(t0);
    write_image((fs::path(dir.path()) / (name + layout::kImageExt)).string(), img);
    ++r.views;
  }
  Json info = info_base;
  info["render_seconds"] = r.render_seconds;
  write_file_atomic((fs::path(dir.path()) / "info.json").string(), info.dump(2) + "\n");
  dir.commit();
  return r;
}

}  // namespace

void NerfRunOptions::validate() const {
  if (dataset.empty()) throw InputError("nerf run options", "dataset is empty: the dataset folder is required");
  if (out.empty()) throw InputError("nerf run options", "out is empty: the run folder is required");
  inputs.validate("nerf run options: inputs");
  if (checkpoint_every < 0)
    throw InputError("nerf run options", "checkpoint_every is " + std::to_string(checkpoint_every) + ", must be >= 0");
  for (int it : snapshot_at)
    if (it < 1) throw InputError("nerf run options", "snapshot_at holds " + std::to_string(it) + ": must be >= 1");
  nerf.validate("nerf run options: nerf");
}

void NerfRenderOptions::validate() const {
  if (model.empty()) throw InputError("nerf render options", "model is empty: the run folder is required");
  if (out.empty()) throw InputError("nerf render options", "out is empty: the renders folder is required");
}

std::string nerf_snapshot_dir(const std::string& run_dir, int iteration) {
  char name[32];
  std::snprintf(name, sizeof name, "iter_%06d", iteration);
  return (fs::path(run_dir) / "snapshots" / name).string();
}

StageOutput nerf_run_output(const std::string& run_dir, const std::string& dataset, const TrainInputs& inputs,
                            const NerfOptions& options) {
  StageOutput s;
  s.record = (fs::path(run_dir) / kRunJson).string();
  if (!fs::exists(s.record)) return s;
  const Json j = read_json_file(s.record);
  if (j.value("format", "") != kNerfRunFormat) {
    s.state = StageOutput::State::kStale;
    s.why = "format: not a radiance field";
    return s;
  }
  const RunRecord want = settings_record(dataset, inputs, options);
  Json data = json_fields::write(want.inputs, kTrainInputsFields);
  data["dataset"] = want.dataset;
  s.why = settings_mismatch(j, data);
  if (s.why.empty()) {
    if (std::string why = settings_mismatch(j.value("options", Json::object()), want.options.to_json()); !why.empty())
      s.why = "options." + why;
  }
  if (!s.why.empty()) s.state = StageOutput::State::kStale;
  else if (j.value("complete", false)) s.state = StageOutput::State::kComplete;
  else if (fs::exists(fs::path(run_dir) / kCheckpointFile)) s.state = StageOutput::State::kPartial;
  return s;  // an incomplete run without a checkpoint is absent: it starts over
}

NerfRunResult train_nerf_run(const NerfRunOptions& o, const NerfIterationCallback& on_iteration) {
  o.validate();
  const Dataset ds = read_dataset(o.dataset);
  const fs::path run(o.out);
  const std::string ckpt = (run / kCheckpointFile).string();
  if (o.resume) {
    const StageOutput s = nerf_run_output(o.out, o.dataset, o.inputs, o.nerf);
    if (s.state == StageOutput::State::kStale)
      throw InputError(s.record, "records other settings (" + s.why + "): resume with those, or start over with --force");
    if (s.state != StageOutput::State::kPartial)
      throw InputError(o.out, s.state == StageOutput::State::kComplete ? "holds a complete run: nothing to resume"
                                                                       : "holds no checkpoint of this run: nothing to resume");
  } else if (fs::exists(run / kRunJson)) {
    if (!o.force) throw InputError(o.out, "already holds a radiance-field run: pass force (--force) to start over");
    for (const char* f : {kRunJson, kFieldFile, kCheckpointFile, "snapshots"}) fs::remove_all(run / f);
  } else if (fs::exists(run) && !fs::is_empty(run)) {
    throw InputError(o.out, "exists and is not a radiance-field run folder: refusing to write into it");
  }
  fs::create_directories(run);
  const auto t_start = std::chrono::steady_clock::now();
  const double cpu_start = process_cpu_seconds();
  std::vector<TrainView> views = load_train_views(ds, o.inputs);

  // The frame covers every camera of the dataset (test views are rendered from it too); the near
  // plane comes from the SfM points the 3DGS methods would start from.
  NerfRunResult result;
  double near = o.nerf.near_m;
  result.near_source = "near_m option";
  if (near <= 0) {
    const std::string pts_dir = o.inputs.points_dir.empty() ? ds.file(layout::kSparseModelDir) : o.inputs.points_dir;
    const fs::path pts_file = fs::path(pts_dir) / "points3D.txt";
    std::vector<ColmapPoint3D> sfm;
    if (fs::exists(pts_file)) sfm = read_colmap_points3d(pts_file.string());
    const std::vector<Eigen::Vector3d> pts = near_plane_points(sfm);
    near = near_from_points(ds.cameras, pts, kMinNearM, kDefaultNearM);
    result.near_source = pts.size() >= kNearMinPoints ? "sfm points: " + std::to_string(pts.size()) + " of " + std::to_string(sfm.size()) +
                                                (pts.size() < sfm.size() ? " (track >= " + std::to_string(kNearMinTrack) + ")" : "")
                                          : "default (no SfM points)";
  }
  result.near_m = near;
  const FrustumFrame frame = forward_facing_frame(ds.cameras, near);
  NerfTrainer trainer(std::move(views), frame, o.nerf);
  // Snapshots and checkpoints are not training: their wall and CPU seconds are left out of the clocks.
  double excluded = 0, excluded_cpu = 0;
  auto not_training = [&](const auto& work) {
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = process_cpu_seconds();
    work();
    excluded += seconds_since(t0);
    excluded_cpu += process_cpu_seconds() - c0;
  };
  double seconds_before = 0;
  std::optional<double> cpu_before = 0.0;
  if (o.resume) {
    not_training([&] {
      const Json state = trainer.load_checkpoint(ckpt);
      const JsonReader r(state, ckpt, "/run_state");
      seconds_before = r.get<double>("train_seconds");
      cpu_before = r.get_optional<double>("train_cpu_seconds");
      r.finish();
    });
  }
  auto elapsed = [&] { return seconds_before + seconds_since(t_start) - excluded; };
  auto elapsed_cpu = [&]() -> std::optional<double> {
    if (!cpu_before) return std::nullopt;
    return *cpu_before + process_cpu_seconds() - cpu_start - excluded_cpu;
  };
  auto info_json = [&](bool complete, double seconds, std::optional<double> cpu_seconds) {
    const GridDims d = trainer.field().dims();
    RunRecord rec = settings_record(o.dataset, o.inputs, o.nerf);
    rec.complete = complete;
    rec.iterations = trainer.iteration();
    rec.train_seconds = seconds;
    rec.train_cpu_seconds = cpu_seconds;
    rec.peak_rss_mb = peak_rss_mb();
    rec.lattice = {d.nu, d.nv, d.nw};
    rec.occupied_cells = trainer.field().occupied_cells();
    rec.near_m = near;
    rec.near_source = result.near_source;
    rec.frame = frame;
    return run_json(rec);
  };
  write_file_atomic((run / kRunJson).string(), info_json(false, seconds_before, cpu_before).dump(2) + "\n");
  std::vector<int> snaps;
  for (int it : o.snapshot_at)
    if (it < o.nerf.iterations) snaps.push_back(it);
  while (trainer.iteration() < o.nerf.iterations) {
    const NerfIterationStats st = trainer.step();
    if (on_iteration) on_iteration(st);
    if (std::find(snaps.begin(), snaps.end(), st.iteration) != snaps.end()) {
      const double train_s = elapsed();
      not_training([&] {
        render_views(trainer.field(), ds, ds.split(o.snapshot_split), o.nerf.march,
                     nerf_snapshot_dir(o.out, st.iteration),
                     Json{{"method", o.method},
                          {"train_seconds", train_s},
                          {"peak_rss_mb", peak_rss_mb()},
                          {"iterations", st.iteration},
                          {"lattice_points", st.lattice_points}});
      });
    }
    if (o.checkpoint_every > 0 && st.iteration % o.checkpoint_every == 0 && st.iteration < o.nerf.iterations) {
      const double train_s = elapsed();
      const std::optional<double> train_cpu = elapsed_cpu();
      not_training([&] {
        Json state{{"train_seconds", train_s}};
        if (train_cpu) state["train_cpu_seconds"] = *train_cpu;
        trainer.save_checkpoint(ckpt, state);
        write_file_atomic((run / kRunJson).string(), info_json(false, train_s, train_cpu).dump(2) + "\n");
      });
    }
  }
  result.train_seconds = elapsed();
  result.train_cpu_seconds = elapsed_cpu();
  trainer.field().save((run / kFieldFile).string());
  result.iterations = trainer.iteration();
  result.peak_rss_mb = peak_rss_mb();
  result.lattice_points = trainer.field().dims().points();
  result.occupied_cells = trainer.field().occupied_cells();
  write_file_atomic((run / kRunJson).string(), info_json(true, result.train_seconds, result.train_cpu_seconds).dump(2) + "\n");
  fs::remove(ckpt);
  return result;
}

NerfRenderResult render_nerf_run(const NerfRenderOptions& o) {
  o.validate();
  const RunRecord ri = read_run_info(o.model);
  if (!ri.complete) throw InputError((fs::path(o.model) / kRunJson).string(), "the run is not complete: train it first");
  const RadianceField field = RadianceField::load((fs::path(o.model) / kFieldFile).string());
  const Dataset ds = read_dataset(o.dataset.empty() ? ri.dataset : o.dataset);
  const MarchSettings& march = ri.options.march;
  std::vector<std::string> all_views;
  for (const Camera& c : ds.cameras) all_views.push_back(c.name);
  const std::vector<std::string>& names = o.split == "all" ? all_views : ds.split(o.split);
  Json info{{"method", o.method},
            {"train_seconds", ri.train_seconds},
            {"peak_rss_mb", std::max(ri.peak_rss_mb, peak_rss_mb())},
            {"iterations", ri.iterations},
            {"lattice_points", field.dims().points()}};
  if (ri.train_cpu_seconds) info["train_cpu_seconds"] = *ri.train_cpu_seconds;
  return render_views(field, ds, names, march, o.out, info);
}

}  // namespace weathergs::nerf
