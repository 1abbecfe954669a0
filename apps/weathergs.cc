// The `weathergs` binary: global flags, subcommand dispatch and the mapping of errors to exit codes.
#include <fmt/core.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <new>

#include "apps/command.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_reader.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/version.h"

namespace weathergs::cli {

namespace {
std::map<std::string, CommandFactory>& registry() {
  static std::map<std::string, CommandFactory> r;  // sorted: stable --help
  return r;
}
}  // namespace

bool register_command(const char* name, CommandFactory factory) {
  registry()[name] = factory;
  return true;
}

void write_text_output(const std::string& path, const std::string& text) {
  if (path.empty() || path == "-") {
    std::fputs(text.c_str(), stdout);
  } else {
    write_file_atomic(path, text);
    std::fprintf(stderr, "wrote %s\n", path.c_str());
  }
}

std::string recorded_command(const std::string& name, const CLI::App& sub) {
  auto quoted = [](const std::string& v) {
    if (!v.empty() && v.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-+=.,/:@%") ==
                          std::string::npos)
      return v;
    std::string q = "'";
    for (char c : v) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  std::string cmd = "weathergs " + name;
  for (const CLI::Option* o : sub.get_options()) {
    if (o->count() == 0 || o->get_lnames().empty()) continue;
    const std::string flag = " --" + o->get_lnames()[0];
    if (o->get_expected_max() == 0) {  // a flag: its result is "true", which would not parse after it
      cmd += flag;
      continue;
    }
    const size_t group = size_t(std::max(1, o->get_type_size()));
    const std::vector<std::string>& r = o->results();
    for (size_t i = 0; i < r.size(); i += group) {
      cmd += flag;
      for (size_t j = i; j < std::min(r.size(), i + group); ++j) cmd += " " + quoted(r[j]);
    }
  }
  return cmd;
}

}  // namespace weathergs::cli

namespace {
// Runs the parsed command and maps what it throws to the documented exit codes (docs/architecture.md):
// bad input and environment problems are 2, a diverged computation 4, broken invariants 3.
int run_command(std::vector<weathergs::cli::Command>& commands) {
  using namespace weathergs;
  using namespace weathergs::cli;
  try {
    for (Command& c : commands)
      if (c.app->parsed()) return c.run();
    return kExitBadInput;
  } catch (const InputError& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return kExitBadInput;
  } catch (const std::filesystem::filesystem_error& e) {
    // An unwritable output, a full disk, a missing folder: the environment, not a bug.
    std::string paths = e.path1().string();
    if (!e.path2().empty()) paths += ", " + e.path2().string();
    fmt::print(stderr, "error: {}: {}\n", paths.empty() ? "file system" : paths, e.code().message());
    return kExitBadInput;
  } catch (const nlohmann::json::exception& e) {
    // Library code parses JSON through JsonReader; this catches a malformed document read elsewhere.
    fmt::print(stderr, "error: malformed JSON: {}\n", e.what());
    return kExitBadInput;
  } catch (const std::bad_alloc&) {
    fmt::print(stderr, "error: out of memory (reduce the resolution, the number of views or of Gaussians)\n");
    return kExitBadInput;
  } catch (const NumericalDivergence& e) {
    fmt::print(stderr, "diverged: {}\n", e.what());
    return kExitDiverged;
  } catch (const InternalError& e) {
    fmt::print(stderr, "internal error (please report): {}\n", e.what());
    return kExitInternal;
  } catch (const std::exception& e) {
    fmt::print(stderr, "internal error (please report): unexpected {}\n", e.what());
    return kExitInternal;
  }
}
}  // namespace

int main(int argc, char** argv) {
  using namespace weathergs;
  using namespace weathergs::cli;
  CLI::App app{"weathergs: synthetic adverse-weather benchmarks for 3D reconstruction, the WeatherGS "
               "pipeline, and evaluation against clean ground truth.\n"
               "Exit codes: 0 ok, 1 a check failed, 2 bad input, usage or environment, 3 internal error, "
               "4 a computation diverged (e.g. training)."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("weathergs 0.1.0 (") + source_commit() + ")");
  bool quiet = false;
  int threads = 0;
  app.add_flag("-q,--quiet", quiet, "No progress bars")->configurable(false);
  app.add_option("-j,--threads", threads, "Worker threads (0 = all cores)")
      ->check(CLI::NonNegativeNumber);

  std::vector<Command> commands;
  for (const auto& [name, factory] : registry()) commands.push_back(factory(app));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Name an unknown command instead of CLI11's generic "A subcommand is required".
    if (app.get_subcommands().empty()) {
      for (int i = 1; i < argc; ++i) {
        std::string arg = argv[i];
        if (arg == "-j" || arg == "--threads") { ++i; continue; }
        if (!arg.empty() && arg[0] != '-') {
          std::fprintf(stderr, "error: unknown command '%s'; run 'weathergs --help' for the list\n", arg.c_str());
          return kExitBadInput;
        }
      }
    }
    int code = app.exit(e);
    return code == 0 ? kExitOk : kExitBadInput;
  }
  set_quiet(quiet);
  set_num_threads(threads);
  return run_command(commands);
}
