#include "methods/reconstruct.h"

#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/dataset_layout.h"
#include "core/error.h"
#include "core/json_reader.h"
#include "core/parallel.h"
#include "evaluator/recipe.h"
#include "restoration/led/detect_dataset.h"
#include "restoration/aef/filter_dataset.h"
#include "methods/backend.h"
#include "methods/recipe.h"
#include "reconstruction/run.h"

namespace weathergs::methods {

namespace fs = std::filesystem;

namespace {

constexpr const char* kModelDir = "model";
constexpr const char* kRendersDir = "renders/test";
constexpr const char* kResultsFile = "results.json";
constexpr const char* kCurveFile = "curve.json";
constexpr const char* kSnapshotRendersDir = "renders/snapshot";  // scratch: removed after scoring
constexpr const char* kFilteredDir = "filtered";
constexpr const char* kDetectedDir = "detected";

// What every stage of one run shares: its options, the method's row, the dataset and the run folder.
struct Run {
  const ReconstructOptions& o;
  const MethodSpec& method;
  const Dataset& ds;
  const fs::path dir;
  const StageCallback& on_stage;
  void stage(const std::string& s) const {
    if (on_stage) on_stage(s);
  }
  const Recipe& recipe() const { return method.recipe; }
};

// The one rule for a stage output left by an earlier run (docs/methods.md, "Resuming"): the part that
// owns the stage judges it against what this run asks for, and an output made with other settings is
// refused, naming the stage, the setting and --force (which starts the run over), rather than mixing
// outputs of two recipes.
const StageOutput& current_or_refuse(const StageOutput& s, const std::string& stage) {
  if (s.state == StageOutput::State::kStale)
    throw InputError(s.record, "holds " + stage + " made with other settings than this run asks for (" + s.why +
                                   "): pass --force to redo the run from scratch");
  return s;
}

void require_files(const std::vector<std::string>& paths, const std::string& what, const std::string& how) {
  for (const std::string& p : paths)
    if (!fs::is_regular_file(p)) throw InputError(p, what + " not found; " + how);
}

// What the run will need, checked before it makes the run folder or starts any stage, so that a
// missing resource costs seconds rather than a training run.
void check_resources(const ReconstructOptions& o) {
  check_writable_destination(o.out, "the run folder (--out)");
  evaluator::check_scoring_resources(o.scoring);
  const Recipe& r = spec(o.method).recipe;
  if (r.needs_led_weights())
    require_files({o.led_weights + ".json", o.led_weights + ".bin"}, "the Lens Effect Detector's weights",
                  "pass --led-weights STEM or set WEATHERGS_LED_WEIGHTS (weathergs ships models/led/led)");
  if (r.needs_aef_weights()) {
    std::vector<std::string> files;
    for (const char* n : {"derain", "desnow", "selector"})
      for (const char* ext : {".json", ".bin"}) files.push_back((fs::path(o.aef_weights) / (std::string(n) + ext)).string());
    require_files(files, "the learned AEF's weights",
                  "pass --aef-weights DIR or set WEATHERGS_AEF_WEIGHTS (weathergs ships models/aef)");
  }
}

// The run folder: a complete run is refused unless --force, which removes everything.
void open_run_folder(const ReconstructOptions& o) {
  const fs::path run(o.out);
  if (fs::exists(run / kResultsFile) && !o.force)
    throw InputError(o.out, "already holds a complete run (results.json): pass --force to redo it");
  if (o.force) fs::remove_all(run);
  fs::create_directories(run);
}

struct Points {
  std::string dir;             // empty: the trainer's random initialization
  std::string initialization;  // how the model starts, for results.json
};

// COLMAP with the known poses into the run folder (the dataset itself is never modified).
Points triangulate_into_run(const Run& run, const fs::path& local) {
  run.stage("triangulating (COLMAP, known poses): the dataset has no SfM points");
  capture::TriangulateOptions t;
  t.images = run.recipe().clean_points ? capture::TriangulateImages::kClean : capture::TriangulateImages::kImages;
  t.views = capture::TriangulateViews::kAll;
  t.colmap = run.o.colmap;
  t.force = true;
  t.model_dir = local.string();
  t.logs_dir = (run.dir / layout::kLogsDir / "colmap").string();
  fs::create_directories(local.parent_path());
  try {
    const capture::TriangulationResult tr = capture::triangulate_dataset(run.o.dataset, t);
    if (capture::has_sfm_points(local.string()))
      return {local.string(), "triangulated: " + std::to_string(tr.stats.points) + " points"};
  } catch (const InputError& e) {
    run.stage(std::string("warning: triangulation failed, using the random initialization: ") + e.what());
  }
  return {"", "random (COLMAP found no points)"};
}

// 1. SfM points: the dataset's, else those an earlier run triangulated, else triangulated now.
Points points_stage(const Run& run) {
  const char* model = run.recipe().clean_points ? layout::kSparseCleanModelDir : layout::kSparseModelDir;
  const std::string dataset_points = run.ds.file(model);
  if (dataset_has_points(run.ds, run.o.method))
    return {dataset_points, "dataset " + fs::relative(dataset_points, run.ds.root).string()};
  if (run.o.points != PointsPolicy::kAuto) return {"", "random (the dataset has no SfM points)"};
  const fs::path local = run.dir / model;
  if (capture::has_sfm_points(local.string())) return {local.string(), "triangulated (earlier run)"};
  return triangulate_into_run(run, local);
}

// 2. The AEF on every view, kept when an earlier run made it with these settings.
void filter_stage(const Run& run) {
  if (!run.recipe().particle_filter) return;
  const restoration::aef::FilterDatasetOptions f = aef_stage_options(run.o);
  const std::string out = (run.dir / kFilteredDir).string();
  const int width = run.ds.cameras.empty() ? 0 : run.ds.cameras.front().width;
  if (current_or_refuse(restoration::aef::filter_output(out, f, width), "AEF images").state == StageOutput::State::kComplete)
    return;
  run.stage(std::string("filtering particles (AEF: ") + restoration::aef::to_string(run.recipe().aef) + ") on every view");
  restoration::aef::filter_dataset(run.o.dataset, out, f);
}

// 3. The LED on the raw views (method.h says why), averaged over the training views unless the
// method asks for per-view maps (which also rules out adapting to drops fixed to the lens).
void detect_stage(const Run& run) {
  if (!run.recipe().lens_detector) return;
  restoration::led::DetectDatasetOptions d = led_stage_options(run.o);
  const std::optional<adaptation::LedAdaptOptions> adapt = led_stage_adaptation(run.o);
  const Json adaptation = adapt ? adaptation::adaptation_settings_json(*adapt, run.ds.split("train").size()) : Json();
  const std::string out = (run.dir / kDetectedDir).string();
  if (current_or_refuse(restoration::led::detect_output(out, d, adaptation), "LED masks").state ==
      StageOutput::State::kComplete)
    return;
  run.stage("detecting lens drops (LED, averaged over the training views)");
  if (adapt) d.adapt = adaptation::led_adaptation_hook(*adapt);
  restoration::led::detect_dataset(run.o.dataset, out, d);
}

// The method's backend on the inputs its recipe names, snapshots at eval_at's fractions of the run.
std::unique_ptr<Backend> make_backend(const Run& run, const Points& points) {
  const Recipe& r = run.recipe();
  BackendRun b;
  b.dataset = run.o.dataset;
  b.inputs.images = r.images;
  b.inputs.masks = r.masks;
  if (r.particle_filter) b.inputs.images_dir = (run.dir / kFilteredDir).string();
  if (r.lens_detector) b.inputs.masks_dir = (run.dir / kDetectedDir).string();
  b.inputs.points_dir = points.dir;
  b.model_dir = (run.dir / kModelDir).string();
  b.method = run.method.name;
  for (int it : run.o.eval_at)
    if (it < run.o.train.iterations) b.snapshots.push_back({it, run.o.train.iterations});
  if (r.backend == BackendKind::kNerf) {
    nerf::NerfOptions n = run.o.nerf;
    n.seed = run.o.train.seed;
    return make_nerf_backend(std::move(b), n, run.o.checkpoint_every);
  }
  return make_3dgs_backend(std::move(b), method_train_options(run.o), run.o.checkpoint_every);
}

// 4. Training, resumed when an earlier run of the same options stopped part way; a complete model
// made with these options is kept.
TrainOutcome train_stage(const Run& run, Backend& backend, const reconstruction::IterationCallback& on_iteration) {
  const StageOutput s = current_or_refuse(backend.model_output(), run.recipe().backend == BackendKind::kNerf
                                                                     ? "a radiance field"
                                                                     : "a 3DGS model");
  if (s.state == StageOutput::State::kComplete) return {};
  run.stage(std::string(s.state == StageOutput::State::kPartial ? "resuming" : "training") + " " + run.method.name +
            ": " + run.method.description);
  return backend.train(on_iteration);
}

// The sha256 of every weight file the run's restoration stages used, from their own reports:
// {"aef": {"selector": ..., "derain": ...}, "led": ...}. A regression check refuses to compare runs
// made with other weights (evaluator/check.h).
Json weights_record(const Run& run) {
  Json w = Json::object();
  const fs::path filter_report = run.dir / kFilteredDir / restoration::aef::kFilterReportFile;
  if (run.recipe().particle_filter && fs::exists(filter_report)) {
    const Json f = read_json_file(filter_report.string());
    if (f.contains("weights")) {
      Json aef = Json::object();
      for (const auto& [stem, sha] : f.at("weights").items()) aef[fs::path(stem).filename().string()] = sha;
      w["aef"] = aef;
    }
  }
  if (run.recipe().lens_detector)
    w["led"] = restoration::led::read_detect_record((run.dir / kDetectedDir).string()).weights_sha256;
  return w;
}

evaluator::EvaluateOptions scoring(const Run& run, const std::string& renders_dir) {
  evaluator::EvaluateOptions e;
  e.gt_dataset = run.o.dataset;
  e.renders_dir = renders_dir;
  e.method = run.method.name;
  e.scoring = run.o.scoring;
  return e;
}

// 5. The evaluation of the test renders, with what the method's cost and inputs were.
evaluator::Results evaluate_stage(const Run& run, const std::string& renders_dir, const Points& points) {
  run.stage("evaluating against the clean ground truth");
  evaluator::Results res = evaluator::evaluate(scoring(run, renders_dir));
  res.method_info["initialization"] = points.initialization;
  res.method_info["method_description"] = run.method.description;
  res.method_info["weights"] = weights_record(run);
  res.method_info["seed"] = run.o.train.seed;  // pairs runs across methods (leaderboard --paper)
  // The 3DGS schedule is part of the recipe that `check` compares; a radiance field's length is its
  // iterations, which its renders record. Beside it, the length the schedule itself gives this
  // dataset, so that a run with fewer `iterations` is recorded as a short form of the schedule.
  if (run.recipe().backend != BackendKind::kNerf) {
    res.method_info["schedule"] = reconstruction::to_string(run.o.train.schedule);
    reconstruction::TrainOptions own = run.o.train;
    own.iterations = 0;
    res.method_info["schedule_length"] = reconstruction::run_length_for(own, run.ds).iterations;
  }
  // Restoration time is part of a method's cost (Table IV): the AEF's and the LED's own reports.
  auto report_seconds = [&](const fs::path& report) {
    return fs::exists(report) ? read_json_file(report.string()).value("seconds", 0.0) : 0.0;
  };
  if (run.recipe().particle_filter)
    res.method_info["filter_seconds"] = report_seconds(run.dir / kFilteredDir / restoration::aef::kFilterReportFile);
  if (run.recipe().lens_detector) {
    const restoration::led::DetectRecord detect = restoration::led::read_detect_record((run.dir / kDetectedDir).string());
    res.method_info["detect_seconds"] = detect.seconds;
    // A LED that masked nothing on drops that are there must say so, not pass as a result.
    const std::string silent = restoration::led::silent_led_warning(detect);
    if (!silent.empty()) {
      run.stage("warning: " + silent);
      res.method_info["warnings"] = Json::array({silent});
    }
  }
  return res;
}

Json curve_point(const evaluator::Results& res, int iteration) {
  Json p = evaluator::metrics_to_json(res.metrics);
  p["iteration"] = iteration;
  p["train_seconds"] = res.method_info.value("train_seconds", 0.0);
  p["num_gaussians"] = res.method_info.value("num_gaussians", 0);
  return p;
}

// 6. The curve: the same scoring at every snapshot, then the final model.
void curve_stage(const Run& run, Backend& backend, const evaluator::Results& final_results) {
  Json points = Json::array();
  const std::string scratch = (run.dir / kSnapshotRendersDir).string();
  for (int it : backend.snapshots()) {
    run.stage("scoring the snapshot at iteration " + std::to_string(it));
    points.push_back(curve_point(evaluator::evaluate(scoring(run, backend.snapshot_renders(it, scratch))), it));
    fs::remove_all(scratch);
  }
  points.push_back(curve_point(final_results, backend.iterations()));
  const Json curve{{"format", "weathergs-curve"},   {"version", 1},
                   {"method", run.method.name},     {"dataset", final_results.dataset},
                   {"scene", final_results.scene},  {"weather", final_results.weather},
                   {"seed", run.o.train.seed},      {"points", points}};
  write_file_atomic((run.dir / kCurveFile).string(), curve.dump(2) + "\n");
}

// What can be judged once the run's length is resolved, before any stage: an --eval-at iteration
// past the end would never be scored, and a 3DGS method's recipe may rule out a trainer option.
void check_resolved(const ReconstructOptions& o) {
  for (int it : o.eval_at)
    if (it > o.train.iterations)
      throw InputError("--eval-at", std::to_string(it) + " is past the run's " + std::to_string(o.train.iterations) +
                                        " iterations: it would never be scored (the final model always is)");
  if (spec(o.method).recipe.backend == BackendKind::k3dgs)
    method_train_options(o).validate(std::string("--method ") + to_string(o.method));
}

}  // namespace

reconstruction::TrainOptions method_train_options(const ReconstructOptions& o) {
  const Recipe& r = spec(o.method).recipe;
  reconstruction::TrainOptions t = o.train;
  if (r.robust) t.robust = reconstruction::TrainOptions::Robust::kRobustFilter;
  t.distractors_per_view = r.distractors_per_view;
  t.in_the_wild = r.in_the_wild;
  return t;
}

bool dataset_has_points(const Dataset& dataset, Method method) {
  return capture::has_sfm_points(
      dataset.file(spec(method).recipe.clean_points ? layout::kSparseCleanModelDir : layout::kSparseModelDir));
}

void ReconstructOptions::validate() const {
  if (dataset.empty()) throw InputError("reconstruct options", "dataset is empty: the dataset folder is required");
  if (out.empty()) throw InputError("reconstruct options", "out is empty: the run folder is required");
  train.validate("reconstruct options: train");
  if (checkpoint_every < 0) throw InputError("reconstruct options", "checkpoint_every must be >= 0");
  for (int it : eval_at)
    if (it < 1) throw InputError("reconstruct options", "eval_at holds " + std::to_string(it) + ": iterations must be >= 1");
  for (double f : eval_fractions)
    if (!(f > 0 && f <= 1))
      throw InputError("reconstruct options",
                       "eval_fractions (--eval-at-fractions) holds " + std::to_string(f) + ": each must be in (0, 1]");
  colmap.validate();
  led_mask.validate();
  if (led_adapt) led_adapt->validate();
  nerf.validate("reconstruct options: nerf");
  if (spec(method).recipe.needs_aef_weights() && aef_weights.empty())
    throw InputError("reconstruct options", std::string("aef_weights is empty: method ") + to_string(method) +
                                                " needs the learned AEF's weights (--aef-weights)");
  if (spec(method).recipe.needs_led_weights() && led_weights.empty())
    throw InputError("reconstruct options", std::string("led_weights is empty: method ") + to_string(method) +
                                                " needs the Lens Effect Detector's weights (--led-weights)");
}

ReconstructResult reconstruct(const ReconstructOptions& given, const reconstruction::IterationCallback& on_iteration,
                              const StageCallback& on_stage) {
  given.validate();
  check_resources(given);
  const Dataset ds = read_dataset(given.dataset);
  // Files that no longer match their record: refused now, not after training.
  const std::string dataset_sha256 = evaluator::identify_dataset(ds, false).sha256;
  // The run's length and budget for this dataset: snapshots, records and staleness all use them.
  ReconstructOptions o = given;
  o.train = reconstruction::run_length_for(given.train, ds);
  check_resolved(o);
  const Json recipe = run_recipe(o, ds, dataset_sha256);  // what makes runs comparable (evaluator/recipe.h)
  for (double f : given.eval_fractions) o.eval_at.push_back(std::max(1, int(f * o.train.iterations)));
  open_run_folder(o);
  const Run run{o, spec(o.method), ds, fs::path(o.out), on_stage};
  ReconstructResult out;
  const Points points = points_stage(run);
  out.initialization = points.initialization;
  filter_stage(run);
  detect_stage(run);
  const std::unique_ptr<Backend> backend = make_backend(run, points);
  const TrainOutcome trained = train_stage(run, *backend, on_iteration);
  out.resumed = trained.resumed;
  run.stage("rendering the test views");
  const std::string renders_dir = (run.dir / kRendersDir).string();
  fs::create_directories(fs::path(renders_dir).parent_path());
  const RenderOutcome rendered = backend->render("test", renders_dir);
  out.results = evaluate_stage(run, renders_dir, points);
  out.results.method_info[evaluator::kRecipeKey] = recipe;
  out.results.method_info[evaluator::kRecipeFingerprintKey] = evaluator::recipe_fingerprint(recipe);
  out.results.method_info["threads"] = num_threads();  // CPU time = the seconds above x threads (archive status)
  curve_stage(run, *backend, out.results);
  evaluator::write_results((run.dir / kResultsFile).string(), out.results);
  out.train_seconds = out.results.method_info.value("train_seconds", 0.0);
  out.peak_rss_mb = out.results.method_info.value("peak_rss_mb", trained.peak_rss_mb);
  out.render_seconds_per_view = rendered.views > 0 ? rendered.seconds / rendered.views : 0;
  return out;
}

}  // namespace weathergs::methods
