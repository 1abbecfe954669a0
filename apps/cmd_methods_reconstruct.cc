// `weathergs reconstruct`: one method on one dataset, end to end (methods/reconstruct.h, docs/methods.md).
#include <cstdio>
#include <memory>
#include <set>

#include "apps/command.h"
#include "apps/evaluator_flags.h"
#include "apps/resources.h"
#include "apps/train_flags.h"
#include "core/dataset.h"
#include "core/json_reader.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "methods/archive_restore.h"
#include "methods/reconstruct.h"
#include "nerf/trainer.h"
#include "reconstruction/run.h"
#include "reconstruction/unread_settings.h"

namespace weathergs::cli {
namespace {

struct ReconstructArgs {
  methods::ReconstructOptions options;
  std::string method = "3dgs";
  bool no_triangulate = false;
  std::string led_weights, aef_weights;
  double led_threshold = 0;
  std::string nerf_options_file;
  std::set<std::string> nerf_file_keys;  // the keys the --nerf-options file sets
  CLI::Option* nerf_iterations_flag = nullptr;
  bool led_adapt = false;
  int led_adapt_layouts = 0, led_adapt_iterations = 0;  // 0: LedAdaptOptions' defaults
  TrainFlags train;
  ScoringFlags scoring;
  CLI::App* app = nullptr;
  std::string archive;  // <root>/<suite> of the results archive (docs/archive.md)
  bool archive_only = false;
};

// The 3DGS trainer's flags, which a radiance-field method never reads.
constexpr const char* k3dgsFlags[] = {"--train-options", "--downsample-start", "--full-resolution-at",
                                      "--background", "--max-gaussians", "--random-init", "--random-init-count",
                                      "--mask-normalization", "--large-prune", "--large-prune-from",
                                      "--distractor-opacity-weight"};
// Keys a 3DGS method's recipe sets (methods::method_train_options): --train-options may not set them.
constexpr const char* kRecipeKeys[] = {"robust", "distractors_per_view", "in_the_wild"};

// A flag or an options key the run would never read is refused before any work, naming it
// (docs/methods.md, "Options that cannot take effect"): a run must be what its record says. `o` has
// the run's length resolved.
void refuse_unread(const ReconstructArgs& a, const methods::ReconstructOptions& o, const Dataset& ds) {
  const methods::Recipe& r = methods::spec(o.method).recipe;
  const std::string method = std::string("method ") + methods::to_string(o.method);
  auto refuse_if = [&](bool unread, const char* flag, const std::string& why) {
    if (unread && a.app->count(flag) > 0) throw InputError(flag, why);
  };
  const bool nerf = r.backend == methods::BackendKind::kNerf;
  for (const char* flag : k3dgsFlags)
    refuse_if(nerf, flag, "a 3DGS trainer option, and " + method + " trains a radiance field (--nerf-options)");
  for (const char* flag : {"--iterations", "--schedule"})
    refuse_if(nerf && o.eval_at.empty(), flag,
              "the 3DGS run's length, which a radiance-field method reads only as the unit of --eval-at (" + method +
                  " trains --nerf-iterations)");
  for (const char* flag : {"--nerf-iterations", "--nerf-options"})
    refuse_if(!nerf, flag, "a radiance-field option, and " + method + " trains 3DGS");
  for (const char* flag : {"--led-weights", "--led-threshold", "--led-adapt"})
    refuse_if(!r.lens_detector, flag, method + " runs no Lens Effect Detector");
  refuse_if(a.led_threshold <= 0, "--led-threshold",
            "0 would mask every pixel; a threshold is in (0, 1] (left out: the weights' calibrated rule)");
  refuse_if(r.led_per_view, "--led-adapt", method + " uses the LED's per-view maps, which are never adapted (drops that move)");
  refuse_if(!r.needs_aef_weights(), "--aef-weights", method + " runs no learned AEF");
  refuse_if(a.no_triangulate, "--colmap", "--no-triangulate never runs COLMAP");
  refuse_if(methods::dataset_has_points(ds, o.method), "--colmap",
            "the dataset holds the SfM points " + method + " starts from: COLMAP never runs");
  refuse_if(a.scoring.no_lpips, "--lpips-model", "--no-lpips skips LPIPS");
  const int length = nerf ? o.nerf.iterations : o.train.iterations;  // both backends checkpoint
  refuse_if(o.checkpoint_every >= length, "--checkpoint-every",
            std::to_string(o.checkpoint_every) + " is not below the run's " + std::to_string(length) +
                (nerf ? " radiance-field" : "") + " iterations: no checkpoint would come before the end (0: only at the end)");
  if (nerf) {
    const nerf::NerfOptions& n = o.nerf;
    if (a.nerf_options_file.empty()) return;
    const std::string file = a.nerf_options_file;
    if (a.nerf_file_keys.count("seed"))
      throw InputError(file + ":/seed", "the radiance field's seed is the run's --seed");
    for (int at : n.upsample_at)
      if (a.nerf_file_keys.count("upsample_at") && at >= n.iterations)
        throw InputError(file + ":/upsample_at", "holds " + std::to_string(at) + ", not below the run's " +
                                                     std::to_string(n.iterations) + " iterations: that level would never train");
    if (a.nerf_file_keys.count("tv_fraction") && n.tv_density == 0 && n.tv_color == 0)
      throw InputError(file + ":/tv_fraction", "the total variation is off (tv_density and tv_color 0): nothing reads it");
    return;
  }
  for (const char* key : kRecipeKeys)
    if (a.train.has_file_key(key))
      throw InputError(a.train.where(key), std::string(key) + " is what --method sets (" + method + ")");
  reconstruction::RunContext context;
  context.loss_mask = r.masks != reconstruction::TrainMasks::kNone || r.lens_detector || r.robust;
  // Without the dataset's points, COLMAP may find none, and the random initialization then runs.
  context.from_points = methods::dataset_has_points(ds, o.method);
  const reconstruction::TrainOptions t = methods::method_train_options(o);
  t.validate("--method " + std::string(methods::to_string(o.method)));
  if (const auto u = reconstruction::unread_setting(t, context, [&](const std::string& k) { return a.train.is_set(k); }))
    throw InputError(a.train.where(u->key), u->key + " is set, but " + u->why);
}

int run(ReconstructArgs& a) {
  methods::ReconstructOptions o = a.options;
  o.method = methods::parse_method(a.method, "--method");
  o.points = a.no_triangulate ? methods::PointsPolicy::kDataset : methods::PointsPolicy::kAuto;
  o.scoring = a.scoring.options();
  a.train.apply(o.train);
  if (!a.nerf_options_file.empty()) {
    const int iterations = o.nerf.iterations;
    const JsonReader file = JsonReader::from_file(a.nerf_options_file);
    o.nerf = nerf::NerfOptions::from_user_json(file);
    for (const auto& [key, value] : file.value().items()) a.nerf_file_keys.insert(key);
    if (a.nerf_iterations_flag->count() > 0) o.nerf.iterations = iterations;
    o.nerf.validate("--nerf-options " + a.nerf_options_file);
  }
  // The run's length is known before it starts (the progress bar's total); reconstruct() resolves the same.
  const Dataset dataset = read_dataset(o.dataset);
  o.train = reconstruction::run_length_for(o.train, dataset);
  refuse_unread(a, o, dataset);
  const methods::Recipe& recipe = methods::spec(o.method).recipe;
  if (recipe.needs_led_weights()) o.led_weights = find_led_weights(a.led_weights);
  if (recipe.needs_aef_weights()) o.aef_weights = find_aef_weights(a.aef_weights);
  if (a.led_adapt) {
    o.led_adapt = adaptation::LedAdaptOptions{};
    o.led_adapt->threads = num_threads();
    if (a.led_adapt_layouts > 0) o.led_adapt->layouts = a.led_adapt_layouts;
    if (a.led_adapt_iterations > 0) o.led_adapt->iterations = a.led_adapt_iterations;
  }
  if (a.led_threshold > 0) {  // a global threshold: the paper's rule, also for weights with a peak rule
    o.led_mask.rule = restoration::led::LedThresholdRule::kAbove;
    o.led_mask.threshold = a.led_threshold;
  }
  if (!a.archive.empty()) {  // a run the archive holds with this recipe is restored, not trained again
    const methods::RestoreOutcome r = methods::restore_from_archive(o, a.archive);
    if (r.restored) {
      std::printf("restored from archive: %s -> %s\n", r.cell_dir.c_str(), o.out.c_str());
      return kExitOk;
    }
    if (a.archive_only) {
      std::fprintf(stderr, "not restored: %s\n", r.why.c_str());
      return kExitCheckFailed;
    }
    if (!is_quiet()) std::fprintf(stderr, "reconstruct: not restored (%s): running it\n", r.why.c_str());
  }
  const bool nerf = recipe.backend == methods::BackendKind::kNerf;
  const int total = nerf ? o.nerf.iterations : o.train.iterations;
  ProgressBar bar("train", total);
  int reported = 0;
  auto on_iteration = [&](const reconstruction::IterationStats& st) {
    if (reported++ == 0) bar.resume_at(st.iteration - 1);  // a resumed run starts part way
    if (st.iteration % 10 == 0 || st.iteration == total) {
      char s[120];
      if (nerf)
        std::snprintf(s, sizeof s, "it %d loss %.5f psnr %.2f", st.iteration, st.loss, st.psnr);
      else
        std::snprintf(s, sizeof s, "it %d loss %.4f n %lld", st.iteration, st.loss, static_cast<long long>(st.num_gaussians));
      bar.set_status(s);
    }
    bar.tick();
  };
  auto on_stage = [&](const std::string& s) {
    if (!is_quiet()) std::fprintf(stderr, "reconstruct: %s\n", s.c_str());
  };
  const methods::ReconstructResult r = methods::reconstruct(o, on_iteration, on_stage);
  bar.finish();
  const evaluator::Results& res = r.results;
  std::printf("%s on %s (%zu test views): PSNR %s  SSIM %s  LPIPS %s | train %.1f s, render %.1f ms/view, "
              "peak %.0f MiB | init: %s\nwrote %s/results.json\n",
              res.method.c_str(), res.dataset.c_str(), res.per_view.size(),
              evaluator::format_metric(res.metrics.psnr, 2).c_str(), evaluator::format_metric(res.metrics.ssim, 4).c_str(),
              res.metrics.lpips ? evaluator::format_metric(*res.metrics.lpips, 4).c_str() : "skipped", r.train_seconds,
              1000 * r.render_seconds_per_view, r.peak_rss_mb, r.initialization.c_str(), o.out.c_str());
  return kExitOk;
}

Command make(CLI::App& root) {
  auto a = std::make_shared<ReconstructArgs>();
  std::string methods;
  for (methods::Method m : methods::all_methods())
    methods += std::string(methods.empty() ? "" : ", ") + methods::spec(m).name + " (" + methods::spec(m).description + ")";
  CLI::App* sub = root.add_subcommand(
      "reconstruct",
      "Run one method on one dataset end to end: SfM points if missing, training, test renders, evaluation "
      "(RUN/results.json). A stopped run resumes when started again.");
  a->app = sub;
  sub->add_option("--data", a->options.dataset, "Dataset folder")->required();
  sub->add_option("--method", a->method, "Method: " + methods)->capture_default_str();
  sub->add_option("--out", a->options.out, "Run folder")->required();
  a->train.add_to(sub, a->options.train, a->options.checkpoint_every);
  a->nerf_iterations_flag = sub->add_option("--nerf-iterations", a->options.nerf.iterations,
                  "Training iterations of the radiance-field methods (nerf, derainnerf, weathergs-nerf, nerf-oracle; "
                  "batches of " + std::to_string(a->options.nerf.batch_rays) + " rays; docs/nerf.md)")
      ->capture_default_str()->check(CLI::PositiveNumber);
  sub->add_option("--nerf-options", a->nerf_options_file,
                  "NerfOptions of the radiance-field methods as JSON, the keys of their run.json's \"options\" (docs/nerf.md): "
                  "a key it leaves out keeps its default, and --nerf-iterations given on the command line overrides it")
      ->check(CLI::ExistingFile);
  sub->add_option("--eval-at", a->options.eval_at,
                  "Also score the test views at these iterations (comma-separated, e.g. 500,1000,2000): RUN/curve.json "
                  "holds accuracy against training seconds; the radiance-field methods score at the same fractions of their run "
                  "(docs/methods.md)")
      ->delimiter(',');
  sub->add_option("--eval-at-fractions", a->options.eval_fractions,
                  "The same as fractions of the run's length (comma-separated, each in (0, 1), e.g. 0.25,0.5): "
                  "floor(fraction x length), for a length the schedule sets")
      ->delimiter(',');
  sub->add_flag("--force", a->options.force,
                "Start the run over: remove what an earlier run left at --out (a complete run, or stages made with "
                "other settings, which are refused otherwise)");
  sub->add_flag("--no-triangulate", a->no_triangulate,
                "Never run COLMAP: without SfM points in the dataset, use the random initialization");
  sub->add_option("--colmap", a->options.colmap.executable, "COLMAP executable")->capture_default_str();
  sub->add_option("--led-weights", a->led_weights,
                  "Lens Effect Detector weights stem (weathergs, weathergs-no-aef); default $WEATHERGS_LED_WEIGHTS, else "
                  "the installed models/led/led");
  sub->add_option("--aef-weights", a->aef_weights,
                  "Learned AEF weights folder (derain, desnow, selector; weathergs, weathergs-no-led, weathergs-nerf); "
                  "default $WEATHERGS_AEF_WEIGHTS, else the installed models/aef");
  sub->add_option("--led-threshold", a->led_threshold,
                  "LED mask where the attention >= t (default: the weights' calibrated rule, docs/restoration_led.md)")
      ->check(CLI::Range(0.0, 1.0));
  CLI::Option* adapt =
      sub->add_flag("--led-adapt", a->led_adapt,
                    "Adapt the LED to the dataset first (`detect --adapt`: a fine-tune on the training views with new "
                    "lens drops, ~31 s on 2 cores for a quick-profile dataset, ~50 s at the paper profile; "
                    "docs/record/led_adaptation.md)");
  sub->add_option("--led-adapt-layouts", a->led_adapt_layouts,
                  "Drop layouts of --led-adapt (`detect --adapt-layouts`; default 4)")
      ->check(CLI::Range(1, adaptation::kMaxAdaptLayouts))
      ->needs(adapt);
  sub->add_option("--led-adapt-iterations", a->led_adapt_iterations,
                  "A fixed iteration count for --led-adapt (`detect --adapt-iterations`; default ~7 passes over the "
                  "examples; 1 layout x 10 iterations: docs/record/led_adaptation_brief.md)")
      ->check(CLI::Range(1, adaptation::kMaxAdaptIterations))
      ->needs(adapt);
  a->scoring.add_to(sub);
  CLI::Option* archive =
      sub->add_option("--archive", a->archive,
                      "The results archive's suite folder (<root>/<suite>, e.g. benchmarks/results/quick): when it holds "
                      "this run (the dataset's name, the method, the seed) made with the recipe these options give, "
                      "copy its results.json and curve.json into --out instead of running (docs/archive.md)");
  sub->add_flag("--archive-only", a->archive_only,
                "Never run: restore from --archive (exit 0) or say why not (exit 1: not archived, or archived with "
                "another recipe, naming the first differing key)")
      ->needs(archive);
  return {sub, [a] { return run(*a); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(reconstruct, weathergs::cli::make)
