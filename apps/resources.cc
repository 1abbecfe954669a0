#include "apps/resources.h"

#include <cstdlib>
#include <filesystem>

#include "core/error.h"

namespace weathergs::cli {

namespace fs = std::filesystem;

namespace {
std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v ? std::string(v) : std::string();
}
}  // namespace

std::string executable_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw InputError("/proc/self/exe", "cannot locate the weathergs executable: " + ec.message());
  return exe.parent_path().string();
}

std::vector<std::string> data_dirs() {
  const fs::path bin = executable_dir();
  return {bin.string(), (bin.parent_path() / "share" / "weathergs").lexically_normal().string()};
}

std::string find_blender_script(const std::string& flag) {
  if (!flag.empty()) return flag;
  if (std::string e = env("WEATHERGS_BLENDER_SCRIPT"); !e.empty()) return e;
  std::string searched;
  for (const std::string& d : data_dirs()) {
    const fs::path p = fs::path(d) / "blender_scripts" / "render_scene.py";
    if (fs::is_regular_file(p)) return p.string();
    searched += "\n  " + p.string();
  }
  throw InputError("blender script", "render_scene.py not found. Searched:" + searched +
                                         "\nInstall weathergs (cmake --install) or set WEATHERGS_BLENDER_SCRIPT.");
}

std::string find_led_weights(const std::string& flag) {
  if (!flag.empty()) return flag;
  if (std::string e = env("WEATHERGS_LED_WEIGHTS"); !e.empty()) return e;
  std::string searched;
  for (const std::string& d : data_dirs()) {
    const fs::path stem = fs::path(d) / "models" / "led" / "led";
    if (fs::is_regular_file(stem.string() + ".json")) return stem.string();
    searched += "\n  " + stem.string() + ".json";
  }
  throw InputError("LED weights", "models/led/led.json not found. Searched:" + searched +
                                      "\nInstall weathergs (cmake --install), pass --weights, set WEATHERGS_LED_WEIGHTS, "
                                      "or retrain with `make models`.");
}

std::string find_aef_weights(const std::string& flag) {
  if (!flag.empty()) return flag;
  if (std::string e = env("WEATHERGS_AEF_WEIGHTS"); !e.empty()) return e;
  std::string searched;
  for (const std::string& d : data_dirs()) {
    const fs::path dir = fs::path(d) / "models" / "aef";
    if (fs::is_regular_file(dir / "selector.json")) return dir.string();
    searched += "\n  " + (dir / "selector.json").string();
  }
  throw InputError("AEF weights", "models/aef/selector.json not found. Searched:" + searched +
                                      "\nInstall weathergs (cmake --install), pass --weights, set WEATHERGS_AEF_WEIGHTS, "
                                      "or retrain with `make models`.");
}

std::vector<std::string> lpips_model_search(const std::string& flag) {
  if (!flag.empty()) return {flag};
  if (std::string e = env("WEATHERGS_LPIPS_MODEL"); !e.empty()) return {e};
  std::vector<std::string> out;
  for (const std::string& d : data_dirs()) out.push_back((fs::path(d) / "models" / "lpips").string());
  return out;
}

std::string cache_dir(const std::string& flag) {
  if (!flag.empty()) return flag;
  if (std::string c = env("WEATHERGS_CACHE"); !c.empty()) return c;
  if (std::string x = env("XDG_CACHE_HOME"); !x.empty()) return x + "/weathergs";
  if (std::string h = env("HOME"); !h.empty()) return h + "/.cache/weathergs";
  throw InputError("cache", "no cache directory: pass --cache DIR or set WEATHERGS_CACHE or HOME");
}

}  // namespace weathergs::cli
