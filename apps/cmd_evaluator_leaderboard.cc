// weathergs leaderboard: the paper's tables from any number of results files.
#include <optional>

#include "apps/command.h"
#include "evaluator/leaderboard.h"
#include "evaluator/paper_agreement.h"
#include "evaluator/paper_tables.h"

namespace weathergs::cli {
namespace {

struct LeaderboardArgs {
  std::vector<std::string> results;
  std::string format = "md", output, against_paper, note;
  bool paper = false;
  bool allow_mixed_data = false;
  bool allow_mixed_recipes = false;
};

int run_leaderboard(const LeaderboardArgs& args) {
  const evaluator::TableFormat format = evaluator::parse_table_format(args.format);
  evaluator::check_note(format, args.note);  // before reading every result
  std::optional<evaluator::PublishedTables> published;
  if (!args.against_paper.empty()) {
    if (format != evaluator::TableFormat::kMarkdown)
      throw InputError("--against-paper", "the agreement section is Markdown: use --format md");
    published = evaluator::read_published_tables(args.against_paper);  // before reading every result
  }
  std::vector<evaluator::LoadedResults> loaded;
  for (const auto& p : args.results) loaded.push_back({p, evaluator::read_results(p)});
  evaluator::LeaderboardOptions options;
  options.allow_mixed_data = args.allow_mixed_data;
  options.allow_mixed_recipes = args.allow_mixed_recipes;
  std::string text;
  if (args.paper || published) {
    const evaluator::PaperTables tables = evaluator::build_paper_tables(loaded, options);
    text = evaluator::render_paper_tables(tables, format, args.note);
    if (published) text += evaluator::render_agreement(tables, *published);
  } else {
    text = evaluator::render_leaderboard(evaluator::build_leaderboard(loaded, options), format, args.note);
  }
  write_text_output(args.output, text);
  return kExitOk;
}

Command make_leaderboard(CLI::App& root) {
  auto args = std::make_shared<LeaderboardArgs>();
  CLI::App* sub = root.add_subcommand("leaderboard", "Build leaderboard tables (one per weather) from results files");
  sub->add_option("results", args->results, "Results JSON files")->required();
  sub->add_option("--format", args->format, "md, csv, latex or html")->capture_default_str();
  sub->add_option("-o,--output", args->output, "Output file (default: stdout)");
  sub->add_flag("--paper", args->paper,
                "The paper's four tables: I snow, II rain (oracle and gt-masks as reference lines), III the "
                "ablation averaged over all variants, IV the cost per method, then paired differences; seeds "
                "give mean ± the 95% Student-t interval (docs/evaluator.md)");
  sub->add_option("--against-paper", args->against_paper,
                  "With the paper's tables, a section setting them beside the published ones in FILE "
                  "(benchmarks/paper_tables.json): rankings with Kendall's tau, each reading reproduced or not "
                  "(implies --paper; Markdown only)")
      ->check(CLI::ExistingFile);
  sub->add_option("--note", args->note,
                  "What the tables are, e.g. 'A smoke run at 1000 iterations, not converged; the converged tables: "
                  "docs/results.md': the first paragraph under the title (md, html), comment lines (latex); refused "
                  "with csv, which holds data only");
  sub->add_flag("--allow-mixed-data", args->allow_mixed_data,
                "Tabulate results of one variant scored on datasets of different identities (refused, exit 2, "
                "otherwise), marking their cells with a dagger and a note naming the identities");
  sub->add_flag("--allow-mixed-recipes", args->allow_mixed_recipes,
                "Tabulate results whose recipes differ where they must agree (a method's options, weights or numerics "
                "across its runs, one backend's numerics, the LPIPS weights; refused, exit 2, otherwise), marking their "
                "cells with a double dagger and a note naming the groups and their first differing keys");
  return {sub, [args] { return run_leaderboard(*args); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(leaderboard, weathergs::cli::make_leaderboard)
