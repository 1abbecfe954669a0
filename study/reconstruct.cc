#include "study/reconstruct.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/colmap_model.h"
#include "core/dataset.h"
#include "core/dataset_layout.h"
#include "core/error.h"
#include "core/json_reader.h"
#include "restoration/detect_dataset.h"
#include "restoration/filter_dataset.h"
#include "restoration/lens_detector.h"

namespace weathergs::study {

namespace fs = std::filesystem;

namespace {

constexpr const char* kModelDir = "model";
constexpr const char* kRendersDir = "renders/test";
constexpr const char* kResultsFile = "results.json";
constexpr const char* kCurveFile = "curve.json";
constexpr const char* kSnapshotRendersDir = "renders/snapshot";  // scratch: removed after scoring
constexpr const char* kFilteredDir = "filtered";
constexpr const char* kDetectedDir = "detected";

bool has_points(const std::string& model_dir) {
  const fs::path p = fs::path(model_dir) / "points3D.txt";
  return fs::exists(p) && !read_colmap_points3d(p.string()).empty();
}

// The one rule for a stage output left by an earlier run (docs/study.md, "Resuming"): its settings
// record must match what this run asks for, else the run is refused, naming the stage, the setting
// and --force (which starts the run over), rather than mixing outputs of two recipes.
InputError stale_stage(const fs::path& record, const std::string& stage, const std::string& why) {
  return InputError(record.string(), "holds " + stage + " made with other settings than this run asks for (" + why +
                                         "): pass --force to redo the run from scratch");
}

// Resuming: the run's detected/ must hold the masks this run asks for (weights, averaging, rule,
// adaptation and its options), else the run would train on other masks than its options and
// results.json say.
void check_resumed_masks(const fs::path& report_path, const restoration::DetectDatasetOptions& d,
                         const std::optional<LedAdaptOptions>& adapt, size_t train_views) {
  const Json report = read_json_file(report_path.string());
  const bool adapted = !report.value("adaptation", Json()).is_null();
  if (adapted != adapt.has_value())
    throw stale_stage(report_path, "LED masks", std::string("made ") + (adapted ? "with" : "without") +
                                                    " --led-adapt, asked for " + (adapted ? "without" : "with") + " it");
  restoration::LensDetector led = restoration::LensDetector::load(d.weights);
  if (adapt) use_adapted_peak_rule(led);
  std::string why = settings_mismatch(
      report, restoration::detect_settings_json(led.metadata().value("weights_sha256", ""), d, d.mask.resolved(led)));
  if (why.empty() && adapt) why = settings_mismatch(report.at("adaptation"), adaptation_settings_json(*adapt, train_views));
  if (!why.empty()) throw stale_stage(report_path, "LED masks", why);
}

void require_files(const std::vector<std::string>& paths, const std::string& what, const std::string& how) {
  for (const std::string& p : paths)
    if (!fs::is_regular_file(p)) throw InputError(p, what + " not found; " + how);
}

// The sha256 of every weight file the run's restoration stages used, from their own reports:
// {"aef": {"selector": ..., "derain": ...}, "led": ...}. A regression check refuses to compare runs
// made with other weights (evaluator/check.h).
Json weights_record(const fs::path& run, const Recipe& r) {
  Json w = Json::object();
  const fs::path filter_report = run / kFilteredDir / restoration::kFilterReportFile;
  if (r.particle_filter && fs::exists(filter_report)) {
    const Json f = read_json_file(filter_report.string());
    if (f.contains("weights")) {
      Json aef = Json::object();
      for (const auto& [stem, sha] : f.at("weights").items()) aef[fs::path(stem).filename().string()] = sha;
      w["aef"] = aef;
    }
  }
  const fs::path detect_report = run / kDetectedDir / restoration::kDetectReportFile;
  if (r.lens_detector && fs::exists(detect_report))
    w["led"] = read_json_file(detect_report.string()).value("weights_sha256", "");
  return w;
}

// What the run will need, checked before it makes the run folder or starts any stage, so that a
// missing resource costs seconds rather than a training run.
void check_resources(const ReconstructOptions& o) {
  check_writable_destination(o.out, "the run folder (--out)");
  evaluator::check_scoring_resources(o.scoring);
  const Recipe r = recipe(o.method);
  if (r.lens_detector)
    require_files({o.led_weights + ".json", o.led_weights + ".bin"}, "the Lens Effect Detector's weights",
                  "pass --led-weights STEM or set WEATHERGS_LED_WEIGHTS (weathergs ships models/led/led)");
  if (r.particle_filter && r.aef == restoration::FilterMethod::kLearned) {
    std::vector<std::string> files;
    for (const char* n : {"derain", "desnow", "selector"})
      for (const char* ext : {".json", ".bin"}) files.push_back((fs::path(o.aef_weights) / (std::string(n) + ext)).string());
    require_files(files, "the learned AEF's weights",
                  "pass --aef-weights DIR or set WEATHERGS_AEF_WEIGHTS (weathergs ships models/aef)");
  }
}

}  // namespace

void ReconstructOptions::validate() const {
  if (dataset.empty()) throw InputError("reconstruct options", "dataset is empty: the dataset folder is required");
  if (out.empty()) throw InputError("reconstruct options", "out is empty: the run folder is required");
  if (iterations < 1) throw InputError("reconstruct options", "iterations " + std::to_string(iterations) + " must be >= 1");
  if (random_init_count < 1) throw InputError("reconstruct options", "random_init_count must be >= 1");
  if (!(distractor_opacity_weight >= 0 && std::isfinite(distractor_opacity_weight)))
    throw InputError("reconstruct options", "distractor_opacity_weight " + std::to_string(distractor_opacity_weight) +
                                                " must be a finite number >= 0");
  if (checkpoint_every < 0) throw InputError("reconstruct options", "checkpoint_every must be >= 0");
  for (int it : eval_at)
    if (it < 1) throw InputError("reconstruct options", "eval_at holds " + std::to_string(it) + ": iterations must be >= 1");
  colmap.validate();
  led_mask.validate();
  if (led_adapt) led_adapt->validate();
  nerf.validate("reconstruct options: nerf");
  if (recipe(method).particle_filter && recipe(method).aef == restoration::FilterMethod::kLearned && aef_weights.empty())
    throw InputError("reconstruct options", std::string("aef_weights is empty: method ") + to_string(method) +
                                                " needs the learned AEF's weights (--aef-weights)");
  if (recipe(method).lens_detector && led_weights.empty())
    throw InputError("reconstruct options", std::string("led_weights is empty: method ") + to_string(method) +
                                                " needs the Lens Effect Detector's weights (--led-weights)");
}

ReconstructResult reconstruct(const ReconstructOptions& o, const recon::IterationCallback& on_iteration,
                              const StageCallback& on_stage) {
  o.validate();
  check_resources(o);
  auto stage = [&](const std::string& s) {
    if (on_stage) on_stage(s);
  };
  const Dataset ds = read_dataset(o.dataset);
  const fs::path run(o.out);
  const fs::path results_path = run / kResultsFile;
  if (fs::exists(results_path) && !o.force)
    throw InputError(o.out, "already holds a complete run (results.json): pass --force to redo it");
  if (o.force) fs::remove_all(run);  // every stage starts over
  fs::create_directories(run);
  const Recipe r = recipe(o.method);
  ReconstructResult out;

  // 1. SfM points: the dataset's, else triangulated into the run folder.
  const std::string dataset_points = ds.file(r.clean_points ? layout::kSparseCleanModelDir : layout::kSparseModelDir);
  std::string points_dir;
  if (has_points(dataset_points)) {
    points_dir = dataset_points;
    out.initialization = "dataset " + fs::relative(dataset_points, ds.root).string();
  } else if (o.points == PointsPolicy::kAuto) {
    const fs::path local = run / (r.clean_points ? layout::kSparseCleanModelDir : layout::kSparseModelDir);
    if (has_points(local.string())) {
      points_dir = local.string();
      out.initialization = "triangulated (earlier run)";
    } else {
      stage("triangulating (COLMAP, known poses): the dataset has no SfM points");
      datagen::TriangulateOptions t;
      t.images = r.clean_points ? datagen::TriangulateImages::kClean : datagen::TriangulateImages::kImages;
      t.views = datagen::TriangulateViews::kAll;
      t.colmap = o.colmap;
      t.force = true;
      t.model_dir = local.string();
      t.logs_dir = (run / layout::kLogsDir / "colmap").string();
      fs::create_directories(local.parent_path());
      try {
        const datagen::TriangulationResult tr = datagen::triangulate_dataset(o.dataset, t);
        if (has_points(local.string())) {
          points_dir = local.string();
          out.initialization = "triangulated: " + std::to_string(tr.stats.points) + " points";
        }
      } catch (const InputError& e) {
        stage(std::string("warning: triangulation failed, using the random initialization: ") + e.what());
      }
      if (points_dir.empty()) out.initialization = "random (COLMAP found no points)";
    }
  }
  if (out.initialization.empty()) out.initialization = "random (the dataset has no SfM points)";

  // 2. Restoration: the AEF on every view (kept when an earlier run made it with these settings).
  if (r.particle_filter) {
    restoration::FilterDatasetOptions f;
    f.filter = o.particle_filter;
    f.method = r.aef;
    if (r.aef == restoration::FilterMethod::kLearned) {
      f.task = restoration::AefTask::kAuto;  // the selector decides, per scene, which plugin (or none)
      f.aef_weights = o.aef_weights;
    }
    const fs::path report = run / kFilteredDir / restoration::kFilterReportFile;
    if (fs::exists(report)) {
      const std::string why = restoration::filter_settings_mismatch(read_json_file(report.string()), f,
                                                                    ds.cameras.empty() ? 0 : ds.cameras.front().width);
      if (!why.empty()) throw stale_stage(report, "AEF images", why);
    } else {
      stage(std::string("filtering particles (AEF: ") + restoration::to_string(r.aef) + ") on every view");
      restoration::filter_dataset(o.dataset, (run / kFilteredDir).string(), f);
    }
  }

  // 2b. The LED on the raw views (method.h says why), averaged over the training views.
  if (r.lens_detector) {
    restoration::DetectDatasetOptions d;
    d.weights = o.led_weights;
    d.mask = o.led_mask;
    if (r.led_per_view) d.averaging = restoration::LedAveraging::kPerView;
    std::optional<LedAdaptOptions> adapt;
    if (o.led_adapt && !r.led_per_view) adapt = *o.led_adapt;
    const fs::path detect_report = run / kDetectedDir / restoration::kDetectReportFile;
    if (fs::exists(detect_report)) {
      check_resumed_masks(detect_report, d, adapt, ds.split("train").size());
    } else {
      stage("detecting lens drops (LED, averaged over the training views)");
      if (adapt) d.adapt = led_adaptation_hook(*adapt);
      restoration::detect_dataset(o.dataset, (run / kDetectedDir).string(), d);
    }
  }

  // 3. Training (resumed when an earlier run of the same options stopped part way), 4. test renders.
  TrainInputs inputs;
  inputs.images = r.images;
  inputs.masks = r.masks;
  if (r.particle_filter) inputs.images_dir = (run / kFilteredDir).string();
  if (r.lens_detector) inputs.masks_dir = (run / kDetectedDir).string();
  inputs.points_dir = points_dir;
  const std::string model_dir = (run / kModelDir).string(), renders_dir = (run / kRendersDir).string();
  fs::create_directories(fs::path(renders_dir).parent_path());
  std::vector<int> snapshots;  // iterations of the curve's snapshots, in the backend's own units
  double render_seconds = 0;
  int render_views = 0, final_iteration = 0;
  if (r.backend == Backend::kNerf) {
    nerf::NerfRunOptions t;
    t.dataset = o.dataset;
    t.inputs = inputs;
    t.out = model_dir;
    t.method = to_string(o.method);
    t.nerf = o.nerf;
    t.nerf.seed = o.seed;
    for (int it : o.eval_at)
      if (it < o.iterations) {
        const int s = std::max(1, int(std::lround(double(it) * t.nerf.iterations / o.iterations)));
        if (s < t.nerf.iterations) snapshots.push_back(s);
      }
    t.snapshot_at = snapshots;
    final_iteration = t.nerf.iterations;
    const fs::path run_json = fs::path(model_dir) / "run.json";
    bool trained = false;
    if (fs::exists(run_json)) {
      const Json j = read_json_file(run_json.string());
      if (j.value("format", "") != nerf::kNerfRunFormat) throw stale_stage(run_json, "a model", "format: not a radiance field");
      if (j.value("complete", false)) {
        if (const std::string why = settings_mismatch(j, Json{{"iterations", t.nerf.iterations}}); !why.empty())
          throw stale_stage(run_json, "a radiance field", why);
        trained = true;
      }
    }
    t.force = !trained;  // no checkpoints: an incomplete radiance-field run starts over
    if (!trained) {
      stage("training " + std::string(to_string(o.method)) + ": " + method_description(o.method));
      const nerf::NerfRunResult tr = train_nerf_run(t, [&](const nerf::NerfIterationStats& st) {
        if (!on_iteration) return;
        recon::IterationStats is;
        is.iteration = st.iteration;
        is.loss = st.loss;
        is.psnr = st.psnr;
        on_iteration(is);
      });
      out.peak_rss_mb = tr.peak_rss_mb;
    }
    stage("rendering the test views");
    nerf::NerfRenderOptions rr;
    rr.model = model_dir;
    rr.dataset = o.dataset;
    rr.method = to_string(o.method);
    rr.out = renders_dir;
    const nerf::NerfRenderResult rres = nerf::render_nerf_run(rr);
    render_seconds = rres.render_seconds;
    render_views = rres.views;
  } else {
    recon::TrainRunOptions t;
    t.dataset = o.dataset;
    t.inputs = inputs;
    t.out = model_dir;
    t.checkpoint_every = o.checkpoint_every;
    for (int it : o.eval_at)
      if (it < o.iterations) t.snapshot_at.push_back(it);
    snapshots = t.snapshot_at;
    final_iteration = o.iterations;
    t.train.iterations = o.iterations;
    t.train.seed = o.seed;
    t.train.random_init_count = o.random_init_count;
    t.train.mask_normalization = o.mask_normalization;
    t.train.large_prune = o.large_prune;
    t.train.large_prune_from = o.large_prune_from;
    if (r.robust) t.train.robust = recon::TrainOptions::Robust::kRobustFilter;
    t.train.distractors_per_view = r.distractors_per_view;
    t.train.distractor_opacity_weight = o.distractor_opacity_weight;
    t.train.in_the_wild = r.in_the_wild;
    const fs::path run_json = run / kModelDir / "run.json";
    bool trained = false;
    if (fs::exists(run_json)) {
      const Json j = read_json_file(run_json.string());
      // The trainer's whole options record: another length, seed or recipe is another model.
      if (const std::string why = settings_mismatch(j.value("options", Json::object()), t.train.to_json()); !why.empty())
        throw stale_stage(run_json, "a 3DGS model", "options." + why);
      trained = j.value("complete", false);
      t.resume = !trained && fs::exists(run / kModelDir / "checkpoint.bin");
      t.force = !trained && !t.resume;
    }
    if (!trained) {
      stage(std::string(t.resume ? "resuming" : "training") + " " + to_string(o.method) + ": " +
            method_description(o.method));
      const recon::TrainRunResult tr = recon::train_run(t, on_iteration);
      out.resumed = t.resume;
      out.peak_rss_mb = tr.peak_rss_mb;
    }
    stage("rendering the test views");
    recon::RenderRunOptions rr;
    rr.model = t.out;
    rr.dataset = o.dataset;
    rr.split = "test";
    rr.method = to_string(o.method);
    rr.out = renders_dir;
    const recon::RenderRunResult rres = recon::render_run(rr);
    render_seconds = rres.render_seconds;
    render_views = rres.views;
  }

  // 5. The evaluation; results.json last.
  stage("evaluating against the clean ground truth");
  evaluator::EvaluateOptions e;
  e.gt_dataset = o.dataset;
  e.renders_dir = renders_dir;
  e.method = to_string(o.method);
  e.scoring = o.scoring;
  out.results = evaluator::evaluate(e);
  out.results.method_info["initialization"] = out.initialization;
  out.results.method_info["method_description"] = method_description(o.method);
  out.results.method_info["weights"] = weights_record(run, r);
  // Restoration time is part of a method's cost (Table IV): the AEF's and the LED's own reports.
  auto report_seconds = [&](const fs::path& report) {
    return fs::exists(report) ? read_json_file(report.string()).value("seconds", 0.0) : 0.0;
  };
  if (r.particle_filter)
    out.results.method_info["filter_seconds"] = report_seconds(run / kFilteredDir / restoration::kFilterReportFile);
  if (r.lens_detector)
    out.results.method_info["detect_seconds"] = report_seconds(run / kDetectedDir / restoration::kDetectReportFile);
  // 6. The curve: the same scoring at the snapshots, then the final model.
  Json points = Json::array();
  auto add_point = [&](const evaluator::Results& res, int iteration) {
    Json p = evaluator::metrics_to_json(res.metrics);
    p["iteration"] = iteration;
    p["train_seconds"] = res.method_info.value("train_seconds", 0.0);
    p["num_gaussians"] = res.method_info.value("num_gaussians", 0);
    points.push_back(p);
  };
  std::vector<int> its = snapshots;
  std::sort(its.begin(), its.end());
  its.erase(std::unique(its.begin(), its.end()), its.end());
  for (int it : its) {
    stage("scoring the snapshot at iteration " + std::to_string(it));
    evaluator::EvaluateOptions se = e;
    if (r.backend == Backend::kNerf) {  // the run kept the renders themselves
      se.renders_dir = nerf::nerf_snapshot_dir(model_dir, it);
      add_point(evaluator::evaluate(se), it);
      continue;
    }
    recon::RenderRunOptions sr;
    sr.model = model_dir;
    sr.dataset = o.dataset;
    sr.method = to_string(o.method);
    sr.snapshot = it;
    sr.out = (run / kSnapshotRendersDir).string();
    recon::render_run(sr);
    se.renders_dir = sr.out;
    add_point(evaluator::evaluate(se), it);
    fs::remove_all(sr.out);
  }
  add_point(out.results, final_iteration);
  const Json curve{{"format", "weathergs-curve"},   {"version", 1},
                   {"method", to_string(o.method)}, {"dataset", out.results.dataset},
                   {"scene", out.results.scene},    {"weather", out.results.weather},
                   {"seed", o.seed},                {"points", points}};
  write_file_atomic((run / kCurveFile).string(), curve.dump(2) + "\n");
  evaluator::write_results(results_path.string(), out.results);
  out.train_seconds = out.results.method_info.value("train_seconds", 0.0);
  out.peak_rss_mb = out.results.method_info.value("peak_rss_mb", out.peak_rss_mb);
  out.render_seconds_per_view = render_views > 0 ? render_seconds / render_views : 0;
  return out;
}

}  // namespace weathergs::study
