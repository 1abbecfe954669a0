// weathergs train: 3D Gaussian Splatting on the CPU (docs/reconstruction.md).
#include <cstdio>

#include "apps/command.h"
#include "apps/train_flags.h"
#include "core/dataset.h"
#include "core/progress.h"
#include "reconstruction/run.h"
#include "reconstruction/unread_settings.h"

namespace weathergs::cli {
namespace {

struct TrainArgs {
  reconstruction::TrainRunOptions run;
  std::string images = "images", masks = "none";
  TrainFlags train;
  CLI::App* app = nullptr;
};

// A value the run would never read is refused before any work, naming where it was set
// (docs/reconstruction.md, "Options that cannot take effect").
void refuse_unread(const TrainArgs& args, const reconstruction::TrainRunOptions& o, const Dataset& dataset) {
  auto given = [&](const char* flag) { return args.app->count(flag) > 0; };
  if (o.resume && given("--force"))
    throw InputError("--force", "starts a run over, and --resume continues the one in --out: give one of them");
  if (!o.inputs.images_dir.empty() && given("--images"))
    throw InputError("--images", "--images-dir replaces the dataset's images: give one source of images");
  if (given("--checkpoint-every") && o.checkpoint_every >= o.train.iterations)
    throw InputError("--checkpoint-every", std::to_string(o.checkpoint_every) + " is not below the run's " +
                                               std::to_string(o.train.iterations) +
                                               " iterations: no checkpoint would come before the end (0: only at the end)");
  reconstruction::RunContext context;
  context.loss_mask = o.inputs.masks != reconstruction::TrainMasks::kNone || !o.inputs.masks_dir.empty() ||
                      o.train.robust != reconstruction::TrainOptions::Robust::kNone;
  context.from_points = reconstruction::starts_from_points(dataset, o.inputs);
  if (const auto u = reconstruction::unread_setting(o.train, context, [&](const std::string& k) { return args.train.is_set(k); }))
    throw InputError(args.train.where(u->key), u->key + " is set, but " + u->why);
}

int run_train(TrainArgs& args) {
  reconstruction::TrainRunOptions o = args.run;
  o.inputs.images = reconstruction::parse_train_images(args.images, "--images");
  o.inputs.masks = reconstruction::parse_train_masks(args.masks, "--masks");
  args.train.apply(o.train);
  if (o.resume) {
    // Start from what the run was trained with; explicitly given flags must agree (checked below
    // through the checkpoint) or extend nothing silently.
    reconstruction::TrainRunOptions stored = reconstruction::read_run_options(o.out);
    auto given = [&](const char* flag) { return args.app->count(flag) > 0; };
    if (!given("--data")) o.dataset = stored.dataset;
    if (!given("--images")) o.inputs.images = stored.inputs.images;
    if (!given("--images-dir")) o.inputs.images_dir = stored.inputs.images_dir;
    if (!given("--masks")) o.inputs.masks = stored.inputs.masks;
    if (!given("--masks-dir")) o.inputs.masks_dir = stored.inputs.masks_dir;
    if (!given("--points-dir")) o.inputs.points_dir = stored.inputs.points_dir;
    if (!given("--iterations")) o.train.iterations = stored.train.iterations;
    if (!given("--schedule")) o.train.schedule = stored.train.schedule;
    if (!given("--seed")) o.train.seed = stored.train.seed;
    if (!given("--background")) o.train.background = stored.train.background;
    if (!given("--random-init-count")) o.train.random_init_count = stored.train.random_init_count;
    if (!given("--random-init")) o.train.random_init = stored.train.random_init;
    if (!given("--max-gaussians")) o.train.max_gaussians = stored.train.max_gaussians;
    if (!given("--distractors-per-view")) o.train.distractors_per_view = stored.train.distractors_per_view;
    if (!given("--distractor-opacity-weight"))
      o.train.distractor_opacity_weight = stored.train.distractor_opacity_weight;
    if (!given("--mask-normalization")) o.train.mask_normalization = stored.train.mask_normalization;
    if (!given("--in-the-wild")) o.train.in_the_wild = stored.train.in_the_wild;
    if (!given("--large-prune")) o.train.large_prune = stored.train.large_prune;
    if (!given("--large-prune-from")) o.train.large_prune_from = stored.train.large_prune_from;
  } else if (o.dataset.empty()) {
    throw InputError("--data", "required (unless --resume)");
  }
  const Dataset dataset = read_dataset(o.dataset);
  o.train = reconstruction::run_length_for(o.train, dataset);
  refuse_unread(args, o, dataset);
  ProgressBar bar("train", o.train.iterations);
  double psnr_ema = 0;
  int reported = 0;
  auto on_iteration = [&](const reconstruction::IterationStats& st) {
    if (reported == 0) bar.resume_at(st.iteration - 1);  // resumed runs start part way
    ++reported;
    psnr_ema = reported == 1 ? st.psnr : 0.9 * psnr_ema + 0.1 * st.psnr;
    if (st.iteration % 10 == 0 || st.iteration == o.train.iterations) {
      char s[160];
      std::snprintf(s, sizeof s, "it %d loss %.4f psnr %.2f n %lld", st.iteration, st.loss, psnr_ema,
                    static_cast<long long>(st.num_gaussians));
      bar.set_status(s);
    }
    bar.tick();
  };
  const reconstruction::TrainRunResult r = reconstruction::train_run(o, on_iteration);
  bar.finish();
  if (!is_quiet())
    std::fprintf(stderr, "trained %d iterations in %.1f s: %lld Gaussians, last train PSNR %.2f dB, peak RSS %.0f MiB\n",
                 r.iterations, r.train_seconds, static_cast<long long>(r.num_gaussians), r.final_psnr, r.peak_rss_mb);
  return kExitOk;
}

Command make_train(CLI::App& root) {
  auto args = std::make_shared<TrainArgs>();
  CLI::App* sub = root.add_subcommand("train", "Train 3D Gaussian Splatting on a dataset's train split (CPU)");
  args->app = sub;
  reconstruction::TrainRunOptions& o = args->run;
  sub->add_option("--data", o.dataset, "Dataset folder (dataset.json, cameras.json, images/)");
  sub->add_option("--images", args->images, "Training images of the dataset: images (with weather) or clean")
      ->capture_default_str()->check(CLI::IsMember({"images", "clean"}));
  sub->add_option("--images-dir", o.inputs.images_dir, "Train on <DIR>/<view>.png instead (e.g. filtered images)");
  sub->add_option("--masks", args->masks,
                  "Ground-truth loss masks of the dataset: none, lens (masks/lens), particles (masks/particles), "
                  "all (either)")
      ->capture_default_str()->check(CLI::IsMember({"none", "lens", "particles", "all"}));
  sub->add_option("--masks-dir", o.inputs.masks_dir, "Loss masks from <DIR>/<view>.png instead (255 = ignore)");
  sub->add_option("--points-dir", o.inputs.points_dir,
                  "Initialize from this COLMAP text model (e.g. DATASET/sparse_clean/0) instead of sparse/0");
  sub->add_option("--distractors-per-view", o.train.distractors_per_view,
                  "DeSplat-style distractor Gaussians per training view, rendered only for their view and never "
                  "exported (the desplat method; 0 = plain 3DGS)")
      ->capture_default_str()->check(CLI::Range(0, 100000));
  sub->add_flag("--in-the-wild", o.train.in_the_wild,
                "gs-w-lite: per-view affine appearance and a learned per-view visibility map with GS-W's (1 - M)^2 "
                "regulariser (docs/reconstruction.md, \"In the wild\")");
  args->train.add_to(sub, o.train, o.checkpoint_every);
  sub->add_option("--out", o.out, "Run folder (run.json, point_cloud.ply, checkpoint.bin)")->required();
  sub->add_flag("--resume", o.resume, "Continue the run in --out from its checkpoint");
  sub->add_flag("--force", o.force, "Start over even if --out already holds a run");
  return {sub, [args] { return run_train(*args); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(train, weathergs::cli::make_train)
