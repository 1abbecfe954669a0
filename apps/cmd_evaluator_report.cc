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

// A word as a POSIX shell reads it back (the command shown under provenance).
std::string shell_quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

int run(ReportArgs& a) {
  a.options.command = "weathergs report " + a.options.suite_dir + " -o " + a.options.out_dir +
                      (a.options.allow_mixed_data ? " --allow-mixed-data" : "") +
                      (a.options.allow_mixed_recipes ? " --allow-mixed-recipes" : "") +
                      (a.options.converged_dir.empty() ? "" : " --converged " + a.options.converged_dir) +
                      (a.options.note.empty() ? "" : " --note " + shell_quoted(a.options.note));
  // The LPIPS weights the scores were made with are this installation's (results record the
  // protocol's name, not the file).
  try {
    const std::string lpips = evaluator::find_lpips_model(lpips_model_search(""));
    a.options.extra_weights.emplace_back("lpips alex v0.1", sha256_file(lpips));
  } catch (const InputError&) {
    // A report can be made where LPIPS is not installed; provenance then lists the runs' own weights.
  }
  const evaluator::ReportSummary s = evaluator::write_report(a.options);
  std::printf("report: %d variants, %d runs, %d test views, %d images, %.1f MB\n", s.variants, s.runs, s.views, s.images,
              double(s.bytes) / 1e6);
  if (!a.options.converged_dir.empty())
    std::printf("converged (archive): %d run%s of these variants from %s (the page's section 'Converged (archive)')\n",
                s.converged_runs, s.converged_runs == 1 ? "" : "s", a.options.converged_dir.c_str());
  std::printf("open %s\n", s.index.c_str());
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
  sub->add_option("--converged", a->options.converged_dir,
                  "A results archive's suite folder (e.g. benchmarks/results/quick): a section 'Converged (archive)' "
                  "with its runs of this suite's variants in the same tables, beside the suite's and never mixed "
                  "into them, and how many cells of its matrix.json hold a run (said plainly when none)");
  sub->add_option("--note", a->options.note,
                  "What the suite is, e.g. 'A smoke run at 1000 iterations, not converged', shown at the top of the "
                  "page");
  a->sub = sub;
  return {sub, [a] { return run(*a); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(report, weathergs::cli::make)
