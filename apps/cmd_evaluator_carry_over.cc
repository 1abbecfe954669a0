// weathergs carry-over FROM TO: whether one results archive's paired differences hold in another.

#include "apps/command.h"
#include "evaluator/carry_over.h"

namespace weathergs::cli {
namespace {

struct CarryOverArgs {
  std::string from, to, output;
  std::string pairs = evaluator::kDefaultCarryOverPairs;
};

int run_carry_over(const CarryOverArgs& args) {
  const auto pairs = evaluator::parse_carry_over_pairs(args.pairs, "--pairs");  // before reading any run
  const std::string text = evaluator::render_carry_over(evaluator::carry_over(args.from, args.to, pairs));
  write_text_output(args.output, text);
  return kExitOk;
}

Command make_carry_over(CLI::App& root) {
  auto args = std::make_shared<CarryOverArgs>();
  CLI::App* sub = root.add_subcommand(
      "carry-over",
      "Whether one results archive's paired differences hold in another (e.g. the quick suite's at the paper "
      "profile): per pair and metric both suites' mean differences over their common variants, a one-sided sign "
      "test and the ratio of the means, as Markdown (docs/evaluator.md)");
  sub->add_option("from", args->from, "The source suite's archive folder, e.g. benchmarks/results/quick")
      ->required()
      ->check(CLI::ExistingDirectory);
  sub->add_option("to", args->to, "The target suite's archive folder, e.g. benchmarks/results/paper")
      ->required()
      ->check(CLI::ExistingDirectory);
  sub->add_option("--pairs", args->pairs, "The differences A - B to test, as A:B[,A:B...]")->capture_default_str();
  sub->add_option("-o,--output", args->output, "Output file (default: stdout)");
  return {sub, [args] { return run_carry_over(*args); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(carry_over, weathergs::cli::make_carry_over)
