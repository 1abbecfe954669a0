// weathergs evaluate: score a method's renders against a dataset's clean ground truth.
#include <cstdio>
#include <filesystem>

#include "apps/command.h"
#include "apps/evaluator_flags.h"

namespace weathergs::cli {
namespace {

struct EvaluateArgs {
  std::string gt, renders, method, split = "test", mask_dir, output, ground_truth = "clean";
  ScoringFlags scoring;
  bool allow_changed_dataset = false;
};

int run_evaluate(const EvaluateArgs& args) {
  evaluator::EvaluateOptions o;
  o.gt_dataset = args.gt;
  o.renders_dir = args.renders;
  o.method = args.method;
  o.split = args.split;
  if (args.ground_truth == "images") o.ground_truth = ImageKind::kImages;
  if (args.ground_truth == "no_particles") o.ground_truth = ImageKind::kTargetNoParticles;
  if (args.ground_truth == "lens_only") o.ground_truth = ImageKind::kTargetLensOnly;
  if (!args.mask_dir.empty()) o.mask_dir = args.mask_dir;
  o.scoring = args.scoring.options();
  o.allow_changed_dataset = args.allow_changed_dataset;
  evaluator::Results r = evaluator::evaluate(o);
  evaluator::write_results(args.output, r);
  if (r.dataset_identity && r.dataset_identity->recorded_sha256)
    std::fprintf(stderr, "warning: scored %s although its files no longer match the identity its dataset.json records "
                 "(%s); results.json says so\n", args.gt.c_str(), r.dataset_identity->first_difference->c_str());
  std::printf("%s on %s (%zu %s views): PSNR %s  SSIM %s  LPIPS %s\nwrote %s\n", r.method.c_str(), r.dataset.c_str(),
              r.per_view.size(), r.protocol.split.c_str(), evaluator::format_metric(r.metrics.psnr, 2).c_str(),
              evaluator::format_metric(r.metrics.ssim, 4).c_str(),
              r.metrics.lpips ? evaluator::format_metric(*r.metrics.lpips, 4).c_str() : "skipped",
              args.output.c_str());
  return kExitOk;
}

Command make_evaluate(CLI::App& root) {
  auto args = std::make_shared<EvaluateArgs>();
  CLI::App* sub = root.add_subcommand("evaluate", "Score renders of a split against the dataset's clean ground truth");
  sub->add_option("--gt", args->gt, "Ground-truth dataset folder (with clean/)")->required();
  sub->add_option("--renders", args->renders, "Folder with <view>.png per split view (+ optional info.json)")->required();
  sub->add_option("--method", args->method, "Method name (default: \"method\" from the renders' info.json)");
  sub->add_option("--split", args->split, "Split to score")->capture_default_str();
  sub->add_option("--ground-truth", args->ground_truth,
                  "Score against: clean (the benchmark), images, or a generator target: no_particles "
                  "(particles removed, lens drops kept: scores a particle filter), lens_only")
      ->capture_default_str()->check(CLI::IsMember({"clean", "images", "no_particles", "lens_only"}));
  sub->add_option("--mask-dir", args->mask_dir, "Masks <view>.png (255 = exclude): metrics over valid pixels only");
  sub->add_option("-o,--output", args->output, "Results JSON to write (atomically)")->required();
  sub->add_flag("--allow-changed-dataset", args->allow_changed_dataset,
                "Score although the dataset's files no longer match the identity its dataset.json records "
                "(refused, exit 2, otherwise); results.json records the difference");
  args->scoring.add_to(sub);
  return {sub, [args] { return run_evaluate(*args); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(evaluate, weathergs::cli::make_evaluate)
