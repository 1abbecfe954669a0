#include "capture/expected_identity.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "capture/process.h"

namespace weathergs::capture {

namespace fs = std::filesystem;

namespace {

constexpr const char* kFormat = "weathergs-expected-identities";

// The first line a command prints (stdout and stderr), or "" when it cannot be run.
std::string first_output_line(const std::vector<std::string>& argv) {
  if (find_executable(argv.front()).empty()) return "";
  const fs::path out = fs::temp_directory_path() / ("weathergs_version_" + std::to_string(::getpid()) + ".txt");
  ProcessOptions o;
  o.log_path = out.string();
  o.timeout_s = 60;
  try {
    run_process(argv, argv.front(), o);
  } catch (const InputError&) {
    return "";
  }
  std::ifstream f(out);
  std::string line;
  while (std::getline(f, line) && line.find_first_not_of(" \t\r") == std::string::npos) {
  }
  std::error_code ec;
  fs::remove(out, ec);
  return line;
}

}  // namespace

Json ToolVersions::to_json() const { return {{"blender", blender}, {"colmap", colmap}}; }

std::string colmap_version(const std::string& executable) {
  const std::string line = first_output_line({executable, "help"});
  const size_t dash = line.find(" -- ");
  return line.substr(0, dash == std::string::npos ? line.size() : dash);
}

std::string blender_version(const std::string& executable) {
  const std::string line = first_output_line({executable, "-v"});
  const std::string prefix = "Blender ";
  return line.rfind(prefix, 0) == 0 ? line.substr(prefix.size()) : line;
}

Json GenerationSettings::to_json() const {
  return {{"weather_spec", weather_spec}, {"max_views", max_views}, {"targets", targets}, {"colmap", colmap}};
}

namespace {

JsonReader read_file_checked(const std::string& path) {
  JsonReader r = JsonReader::from_file(path);
  if (!r.is_object()) throw InputError(r.where(), "expected an object {format, version, profile, variants}");
  const std::string format = r.get<std::string>("format");
  if (format != kFormat) throw InputError(r.where("format"), "expected \"" + std::string(kFormat) + "\"");
  if (r.get<int>("version") != 1) throw InputError(r.where("version"), "unsupported version (expected 1)");
  return r;
}

}  // namespace

std::string describe(const ToolVersions& t) {
  return "Blender " + (t.blender.empty() ? "?" : t.blender) + ", " + (t.colmap.empty() ? "no COLMAP" : t.colmap);
}

std::vector<ToolVersions> expected_tool_versions(const std::string& expected_dir) {
  std::vector<fs::path> files;
  if (fs::is_directory(expected_dir))
    for (const auto& e : fs::directory_iterator(expected_dir))
      if (e.path().extension() == ".json") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  std::vector<ToolVersions> out;
  for (const fs::path& f : files) {
    read_file_checked(f.string());
    const Json all = Json::parse(read_file(f.string()));
    for (const auto& [name, entry] : all.at("variants").items()) {
      ToolVersions t{entry.at("made_with").value("blender", ""), entry.at("made_with").value("colmap", "")};
      if (std::find(out.begin(), out.end(), t) == out.end()) out.push_back(t);
    }
  }
  return out;
}

std::string expected_identities_path(const std::string& scene_file, const std::string& profile) {
  return (fs::path(scene_file).parent_path() / "expected" / (profile + ".json")).string();
}


std::optional<ExpectedIdentity> read_expected_identity(const std::string& path, const std::string& variant) {
  if (!fs::exists(path)) return std::nullopt;
  JsonReader r = read_file_checked(path);
  r.get<std::string>("profile");
  const JsonReader variants = r.child("variants");
  if (!variants.is_object()) throw InputError(variants.where(), "expected an object of variant -> entry");
  r.finish();
  if (!variants.has(variant)) return std::nullopt;
  JsonReader e = variants.child(variant);
  ExpectedIdentity x;
  x.variant = variant;
  JsonReader s = e.child("settings");
  x.settings.weather_spec = s.value().at("weather_spec");
  s.mark("weather_spec");
  x.settings.max_views = s.get<int>("max_views");
  x.settings.targets = s.get<bool>("targets");
  x.settings.colmap = s.get<bool>("colmap");
  s.finish();
  JsonReader m = e.child("made_with");
  x.made_with.blender = m.get<std::string>("blender");
  x.made_with.colmap = m.get<std::string>("colmap");
  m.finish();
  x.weathergs_commit = e.get<std::string>("weathergs_commit");
  x.identity = DatasetIdentity::from_json(e.child("identity"));
  if (x.identity.files.empty()) throw InputError(e.where("identity"), "expected the identity with its files");
  e.finish();
  return x;
}

void write_expected_identity(const std::string& path, const std::string& profile, const ExpectedIdentity& x) {
  Json all = {{"format", kFormat}, {"version", 1}, {"profile", profile}, {"variants", Json::object()}};
  if (fs::exists(path)) {
    read_file_checked(path);
    all = Json::parse(read_file(path));
    if (all.value("profile", "") != profile)
      throw InputError(path, "holds the identities of profile \"" + all.value("profile", "") + "\", not \"" + profile + "\"");
  }
  all["variants"][x.variant] = {{"settings", x.settings.to_json()},
                                {"made_with", x.made_with.to_json()},
                                {"weathergs_commit", x.weathergs_commit},
                                {"identity", x.identity.to_json(true)}};
  fs::create_directories(fs::path(path).parent_path());
  write_file_atomic(path, all.dump(1) + "\n");
}

}  // namespace weathergs::capture
