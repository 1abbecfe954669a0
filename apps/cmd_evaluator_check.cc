// weathergs check: regression-check new results against a baseline (exit 1 when something got worse).
#include <cstdio>

#include "apps/command.h"
#include "core/atomic_file.h"
#include "evaluator/check.h"

namespace weathergs::cli {
namespace {

struct CheckArgs {
  std::vector<std::string> baseline, results;
  evaluator::CheckTolerances tol;
  bool allow_other_data = false, allow_other_weights = false, allow_other_recipe = false;
  std::string json_output, tolerances_file;
  CLI::App* sub = nullptr;
};

int run_check(CheckArgs args) {
  if (!args.tolerances_file.empty()) {  // the baseline's tolerances; explicit flags still override
    const evaluator::CheckTolerances file = evaluator::CheckTolerances::from_file(args.tolerances_file);
    if (args.sub->count("--psnr-tol") == 0) args.tol.psnr = file.psnr;
    if (args.sub->count("--ssim-tol") == 0) args.tol.ssim = file.ssim;
    if (args.sub->count("--lpips-tol") == 0) args.tol.lpips = file.lpips;
    args.tol.view_psnr = file.view_psnr;
    args.tol.view_ssim = file.view_ssim;
    args.tol.view_lpips = file.view_lpips;
  }
  std::vector<evaluator::LoadedResults> base, cur;
  for (const auto& p : args.baseline) base.push_back({p, evaluator::read_results(p)});
  for (const auto& p : args.results) cur.push_back({p, evaluator::read_results(p)});
  evaluator::CheckOptions o;
  o.tolerances = args.tol;
  o.allow_other_data = args.allow_other_data;
  o.allow_other_weights = args.allow_other_weights;
  o.allow_other_recipe = args.allow_other_recipe;
  evaluator::CheckReport report = evaluator::check_regression(base, cur, o);
  std::fputs(report.text.c_str(), stdout);
  if (!args.json_output.empty()) write_file_atomic(args.json_output, report.json.dump(2) + "\n");
  return report.passed ? kExitOk : kExitCheckFailed;
}

Command make_check(CLI::App& root) {
  auto args = std::make_shared<CheckArgs>();
  CLI::App* sub = root.add_subcommand(
      "check", "Regression check: exit 1 if any metric got worse than the baseline by more than its tolerance (the means, "
      "and every view with the per-view tolerances); exit 2 if the two are not comparable (protocol, ground truth, "
      "dataset identity, weights, recipe)");
  sub->add_option("--baseline", args->baseline, "Baseline results JSON (repeatable)")->required();
  sub->add_option("--results", args->results, "New results JSON (repeatable)")->required();
  sub->add_option("--psnr-tol", args->tol.psnr, "Allowed PSNR drop in dB")->capture_default_str();
  sub->add_option("--ssim-tol", args->tol.ssim, "Allowed SSIM drop")->capture_default_str();
  sub->add_option("--lpips-tol", args->tol.lpips, "Allowed LPIPS rise")->capture_default_str();
  sub->add_option("--tolerances", args->tolerances_file,
                  "Tolerances file of the baseline ({\"psnr\", \"ssim\", \"lpips\", \"basis\"}, e.g. "
                  "benchmarks/baselines/regression/tolerances.json); --*-tol flags override it");
  sub->add_flag("--allow-other-data", args->allow_other_data,
                "Compare although the new results were scored on other data than the baseline (dataset_identity); "
                "refused (exit 2) otherwise");
  sub->add_flag("--allow-other-weights", args->allow_other_weights,
                "Compare although the new results were made with other weights than the baseline records "
                "(method_info.weights); refused (exit 2) otherwise");
  sub->add_flag("--allow-other-recipe", args->allow_other_recipe,
                "Compare although the recipe differs (method_info.method, method_description, iterations, schedule); "
                "refused (exit 2) otherwise");
  sub->add_option("--json", args->json_output, "Also write the report as JSON to this file");
  args->sub = sub;
  return {sub, [args] { return run_check(*args); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(check, weathergs::cli::make_check)
