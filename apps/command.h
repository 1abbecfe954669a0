// Subcommands of the one `weathergs` binary register themselves from their own cmd_*.cc file:
//
//   namespace { Command make_compare(CLI::App& root) {
//     auto opts = std::make_shared<CompareOptions>();
//     CLI::App* sub = root.add_subcommand("compare", "Score one image pair");
//     sub->add_option("a", opts->a)->required();
//     return {sub, [opts] { return run_compare(*opts); }};
//   } }
//   WGS_REGISTER_COMMAND(compare, make_compare)
//
// Exit codes (README.md, docs/architecture.md): 0 success, 1 a check failed, 2 bad input, usage or
// environment, 3 internal error (a broken invariant), 4 a computation diverged.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <string>

namespace weathergs::cli {

constexpr int kExitOk = 0, kExitCheckFailed = 1, kExitBadInput = 2, kExitInternal = 3, kExitDiverged = 4;

struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;
};
using CommandFactory = Command (*)(CLI::App& root);

bool register_command(const char* name, CommandFactory factory);

// The command line that reproduces a parsed subcommand, for the manifests of trained weights:
// "weathergs <name>" and every option given, in declaration order, as `--option value` once per value
// (options taking a fixed group of values, e.g. `--band LO HI`, once per group), flags as `--flag`;
// values with characters a shell would split on are single-quoted. Replays as the same command.
std::string recorded_command(const std::string& name, const CLI::App& sub);

// A command's text output: to stdout when `path` is empty or "-", else written atomically, saying so
// on stderr (stdout stays the data's).
void write_text_output(const std::string& path, const std::string& text);

}  // namespace weathergs::cli

#define WGS_REGISTER_COMMAND(name, factory) \
  static const bool wgs_registered_##name = ::weathergs::cli::register_command(#name, factory);
