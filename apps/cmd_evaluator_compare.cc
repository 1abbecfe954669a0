// weathergs compare A B: PSNR / SSIM / LPIPS of one image pair.
#include <cstdio>

#include "apps/command.h"
#include "apps/evaluator_flags.h"
#include "core/json_reader.h"

namespace weathergs::cli {
namespace {

struct CompareArgs {
  std::string a, b, mask;
  bool json = false;
  ScoringFlags scoring;
};

int run_compare(const CompareArgs& args) {
  evaluator::ScoringOptions o = args.scoring.options();
  std::unique_ptr<evaluator::Lpips> lpips;
  if (o.lpips) lpips = std::make_unique<evaluator::Lpips>(evaluator::find_lpips_model(o.lpips_model_search));
  Image a = read_image(args.a), b = read_image(args.b);
  Image mask;
  if (!args.mask.empty()) mask = read_mask(args.mask);
  evaluator::MetricValues m = evaluator::score_pair(a, b, o, lpips.get(), args.mask.empty() ? nullptr : &mask,
                                                    args.a + " vs " + args.b);
  if (args.json) {
    std::printf("%s\n", evaluator::metrics_to_json(m).dump().c_str());
  } else {
    std::printf("PSNR  %s dB\nSSIM  %s\nLPIPS %s\n", evaluator::format_metric(m.psnr, 4).c_str(),
                evaluator::format_metric(m.ssim, 6).c_str(),
                m.lpips ? evaluator::format_metric(*m.lpips, 6).c_str() : "skipped");
  }
  return kExitOk;
}

Command make_compare(CLI::App& root) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* sub = root.add_subcommand("compare", "Score one image pair (PSNR, SSIM, LPIPS)");
  sub->add_option("a", args->a, "First image (e.g. a render)")->required();
  sub->add_option("b", args->b, "Second image (e.g. the ground truth)")->required();
  sub->add_flag("--json", args->json, "Print one JSON object with keys psnr, ssim, lpips");
  sub->add_option("--mask", args->mask, "Mask PNG: 255 = exclude the pixel (masked metrics)");
  args->scoring.add_to(sub);
  return {sub, [args] { return run_compare(*args); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(compare, weathergs::cli::make_compare)
