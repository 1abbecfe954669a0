// Running external tools (Blender, COLMAP) as child processes: argv arrays (no shell, so
// paths with spaces or quotes are safe), output captured to a log file, an optional time limit.
#pragma once

#include <string>
#include <vector>

namespace weathergs::capture {

struct ProcessOptions {
  std::string log_path;      // stdout and stderr go here (appended); empty: /dev/null
  std::string stdout_path;   // if set, stdout goes here instead (e.g. a query's result)
  double timeout_s = 0;      // 0 = no limit; on expiry the process is killed and an error thrown
  std::vector<std::string> env;  // NAME=VALUE entries set for the child (replacing the parent's NAME)
};

struct ProcessResult {
  int exit_code = 0;  // 128 + signal when killed by a signal
  double seconds = 0;
};

// Full path of an executable: `name` itself if it contains '/', else the first match on PATH.
// Returns "" when none is found or it is not executable.
std::string find_executable(const std::string& name);

// Runs argv[0] (looked up with find_executable). Throws InputError(what, ...) if it cannot be started
// ("not found on PATH") or exceeds the time limit; a non-zero exit code is returned, not thrown.
ProcessResult run_process(const std::vector<std::string>& argv, const std::string& what,
                          const ProcessOptions& options = {});

// The last `max_lines` lines of a text file (for error messages quoting a tool's log); "" if unreadable.
std::string tail_of_file(const std::string& path, int max_lines = 15);

}  // namespace weathergs::capture
