// weathergs report SUITE_DIR -o REPORT_DIR: the results browser, a static site (evaluator/report.h).
#include <cstdio>

#include "apps/command.h"
#include "apps/resources.h"
#include "core/sha256.h"
#include "evaluator/lpips.h"
#include "evaluator/report.h"

namespace weathergs::cli {
namespace {

struct ReportArgs {
  evaluator::ReportOptions options;
  CLI::App* sub = nullptr;
};

int run(ReportArgs& a) {
  a.options.command = "weathergs report " + a.options.suite_dir + " -o " + a.options.out_dir +
                      (a.options.allow_mixed_data ? " --allow-mixed-data" : "") +
                      (a.options.allow_mixed_recipes ? " --allow-mixed-recipes" : "");
  // The LPIPS weights the scores were made with are this installation's (results record the
  // protocol's name, not the file).
  try {
    const std::string lpips = evaluator::find_lpips_model(lpips_model_search(""));
    a.options.extra_weights.emplace_back("lpips alex v0.1", sha256_file(lpips));
  } catch (const InputError&) {
    // A report can be made where LPIPS is not installed; provenance then lists the runs' own weights.
  }
  const evaluator::ReportSummary s = evaluator::write_report(a.options);
  std::printf("report: %d variants, %d runs, %d test views, %d images, %.1f MB\nopen %s\n", s.variants, s.runs, s.views,
              s.images, double(s.bytes) / 1e6, s.index.c_str());
  return kExitOk;
}

Command make(CLI::App& root) {
  auto a = std::make_shared<ReportArgs>();
  CLI::App* sub = root.add_subcommand(
      "report",
      "The results browser: a static site (opens from the file system, no server) with the leaderboard, every "
      "method's renders beside the weathered input and the truth per test view (difference maps, mask overlays, "
      "a synchronized zoom), the curves, the cost and the provenance (docs/evaluator.md)");
  sub->add_option("suite", a->options.suite_dir, "Suite folder (the workflow's output: runs/, data/)")->required();
  sub->add_option("-o,--out", a->options.out_dir, "Report folder (replaced as a whole)")->required();
  sub->add_option("--thumb-width", a->options.thumb_width, "Thumbnail width in pixels")->capture_default_str()->check(CLI::Range(16, 4096));
  sub->add_flag("--allow-mixed-data", a->options.allow_mixed_data,
                "Show runs of one variant scored on datasets of different identities, or on another dataset than "
                "data/<variant> (refused, exit 2, otherwise), marked with a dagger");
  sub->add_flag("--allow-mixed-recipes", a->options.allow_mixed_recipes,
                "Show runs whose recipes differ where they must agree (as leaderboard --allow-mixed-recipes; refused, "
                "exit 2, otherwise), marked with a double dagger");
  a->sub = sub;
  return {sub, [a] { return run(*a); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(report, weathergs::cli::make)
