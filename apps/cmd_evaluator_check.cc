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
  std::string json_output;
};

int run_check(const CheckArgs& args) {
  std::vector<evaluator::LoadedResults> base, cur;
  for (const auto& p : args.baseline) base.push_back({p, evaluator::read_results(p)});
  for (const auto& p : args.results) cur.push_back({p, evaluator::read_results(p)});
  evaluator::CheckReport report = evaluator::check_regression(base, cur, args.tol);
  std::fputs(report.text.c_str(), stdout);
  if (!args.json_output.empty()) write_file_atomic(args.json_output, report.json.dump(2) + "\n");
  return report.passed ? kExitOk : kExitCheckFailed;
}

Command make_check(CLI::App& root) {
  auto args = std::make_shared<CheckArgs>();
  CLI::App* sub = root.add_subcommand(
      "check", "Regression check: exit 1 if any metric got worse than the baseline by more than its tolerance");
  sub->add_option("--baseline", args->baseline, "Baseline results JSON (repeatable)")->required();
  sub->add_option("--results", args->results, "New results JSON (repeatable)")->required();
  sub->add_option("--psnr-tol", args->tol.psnr, "Allowed PSNR drop in dB")->capture_default_str();
  sub->add_option("--ssim-tol", args->tol.ssim, "Allowed SSIM drop")->capture_default_str();
  sub->add_option("--lpips-tol", args->tol.lpips, "Allowed LPIPS rise")->capture_default_str();
  sub->add_option("--json", args->json_output, "Also write the report as JSON to this file");
  return {sub, [args] { return run_check(*args); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(check, weathergs::cli::make_check)
