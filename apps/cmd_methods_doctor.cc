// `weathergs doctor`: is everything a command will need here? Lists each resource (weights, tools,
// scripts, an output folder) with where it was found, or what is missing and how to provide it; with
// --need, exits 2 naming the first missing one, so that scripts check before any long work.
#include <cstdio>
#include <filesystem>
#include <functional>

#include "apps/command.h"
#include "apps/resources.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "capture/expected_identity.h"
#include "capture/process.h"
#include "evaluator/evaluate.h"

namespace weathergs::cli {
namespace {

struct DoctorArgs {
  std::vector<std::string> need;
  std::string blender = "blender", colmap = "colmap", out;
};

struct Resource {
  const char* name;
  const char* what;
  std::function<std::string(const DoctorArgs&)> find;  // the path found; InputError when missing
};

std::string tool(const std::string& name, const char* what, const char* flag) {
  const std::string p = capture::find_executable(name);
  if (p.empty())
    throw InputError(name, std::string(what) + " not found on PATH: install it (scripts/install-deps.sh) or pass " + flag +
                               " PATH");
  return p;
}

// The benchmark's expected identities (scenes/expected/) shipped with this weathergs.
std::string expected_dir() {
  for (const std::string& d : data_dirs()) {
    const std::filesystem::path p = std::filesystem::path(d) / "scenes" / "expected";
    if (std::filesystem::is_directory(p)) return p.string();
  }
  return "";
}

// The tool with its version, and whether the benchmark's identities were made with that version.
std::string tool_with_version(const std::string& path, const std::string& version, const std::string& expected_of_tool) {
  std::string s = path + " (" + (version.empty() ? "version unknown" : version) + ")";
  if (!expected_of_tool.empty())
    s += version == expected_of_tool ? "; the benchmark's identities were made with it"
                                     : "; the benchmark's identities were made with " + expected_of_tool +
                                           ": generated datasets will not match them";
  return s;
}

std::string expected_blender() {
  const auto v = capture::expected_tool_versions(expected_dir());
  return v.empty() ? "" : v.front().blender;
}
std::string expected_colmap() {
  const auto v = capture::expected_tool_versions(expected_dir());
  return v.empty() ? "" : v.front().colmap;
}

std::string require_file(const std::string& p) {
  if (!std::filesystem::is_regular_file(p)) throw InputError(p, "missing");
  return p;
}

const std::vector<Resource>& resources() {
  static const std::vector<Resource> r = {
      {"lpips", "LPIPS v0.1 model (scoring)",
       [](const DoctorArgs&) {
         evaluator::ScoringOptions o;
         o.lpips_model_search = lpips_model_search("");
         evaluator::check_scoring_resources(o);
         return evaluator::find_lpips_model(o.lpips_model_search);
       }},
      {"led", "Lens Effect Detector weights",
       [](const DoctorArgs&) {
         const std::string stem = find_led_weights("");
         require_file(stem + ".bin");
         return stem;
       }},
      {"aef", "learned AEF weights (derain, desnow, selector)",
       [](const DoctorArgs&) {
         const std::string dir = find_aef_weights("");
         for (const char* f : {"derain.json", "derain.bin", "desnow.json", "desnow.bin", "selector.bin"})
           require_file(dir + "/" + f);
         return dir;
       }},
      {"blender", "Blender (scene rendering)",
       [](const DoctorArgs& a) {
         return tool_with_version(tool(a.blender, "Blender", "--blender"), capture::blender_version(a.blender),
                                  expected_blender());
       }},
      {"blender-script", "the Blender scene script", [](const DoctorArgs&) { return find_blender_script(""); }},
      {"colmap", "COLMAP (structure from motion)",
       [](const DoctorArgs& a) {
         return tool_with_version(tool(a.colmap, "COLMAP", "--colmap"), capture::colmap_version(a.colmap),
                                  expected_colmap());
       }},
      {"benchmark-tools", "the tool versions of the benchmark's expected identities (scenes/expected/)",
       [](const DoctorArgs& a) {
         const std::string dir = expected_dir();
         if (dir.empty()) throw InputError("scenes/expected", "not found beside this weathergs (is it installed?)");
         const capture::ToolVersions here{capture::blender_version(a.blender), capture::colmap_version(a.colmap)};
         for (const capture::ToolVersions& t : capture::expected_tool_versions(dir))
           if (!(t == here))
             throw InputError(dir, "made with " + capture::describe(t) + ", this machine has " + capture::describe(here) +
                                       ": generated benchmark datasets will not be the benchmark's (generate refuses them)");
         return dir + ": " + capture::describe(here);
       }},
      {"out", "the output folder (--out)",
       [](const DoctorArgs& a) {
         if (a.out.empty()) throw InputError("--out", "no output folder given");
         check_writable_destination(a.out, "the output folder (--out)");
         return a.out;
       }},
  };
  return r;
}

int run(const DoctorArgs& a) {
  std::vector<std::string> names = a.need;
  if (names.empty())
    for (const Resource& r : resources())
      if (std::string(r.name) != "out" || !a.out.empty()) names.push_back(r.name);
  std::string first_missing;
  for (const std::string& n : names) {
    const Resource* r = nullptr;
    for (const Resource& x : resources())
      if (n == x.name) r = &x;
    if (!r) {
      std::string known;
      for (const Resource& x : resources()) known += std::string(known.empty() ? "" : ", ") + x.name;
      throw InputError("--need", "unknown resource '" + n + "' (known: " + known + ")");
    }
    try {
      std::printf("ok       %-15s %s: %s\n", r->name, r->what, r->find(a).c_str());
    } catch (const InputError& e) {
      std::printf("MISSING  %-15s %s: %s\n", r->name, r->what, e.what());
      if (first_missing.empty()) first_missing = std::string(r->what) + ": " + e.what();
    }
  }
  std::fflush(stdout);
  if (!first_missing.empty() && !a.need.empty()) throw InputError("doctor", first_missing);
  return first_missing.empty() ? kExitOk : kExitCheckFailed;
}

Command make(CLI::App& root) {
  auto a = std::make_shared<DoctorArgs>();
  CLI::App* sub = root.add_subcommand(
      "doctor",
      "Check that what the commands need is here (LPIPS, LED and AEF weights, Blender and its script, COLMAP, an "
      "output folder): one line per resource with its path, or what is missing and how to provide it. Exit 1 if "
      "any is missing; with --need, exit 2 naming the first missing one of those asked for");
  sub->add_option("--need", a->need,
                  "Only these, comma-separated: lpips, led, aef, blender, blender-script, colmap, benchmark-tools, out")
      ->delimiter(',');
  sub->add_option("--blender", a->blender, "Blender executable")->capture_default_str();
  sub->add_option("--colmap", a->colmap, "COLMAP executable")->capture_default_str();
  sub->add_option("--out", a->out, "An output folder the caller will write (checked to be creatable and writable)");
  return {sub, [a] { return run(*a); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(doctor, weathergs::cli::make)
