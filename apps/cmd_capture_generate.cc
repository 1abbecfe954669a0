// `weathergs generate`: a scene variant or the whole benchmark suite, from scene spec to dataset.
#include <cstdio>
#include <filesystem>
#include <memory>

#include "apps/command.h"
#include "core/error.h"
#include "apps/resources.h"
#include "core/parallel.h"
#include "capture/generate.h"
#include "capture/scene_spec.h"
#include "core/json_reader.h"

namespace weathergs::cli {
namespace {

namespace fs = std::filesystem;

struct GenerateArgs {
  std::string scene, weather, suite, out, profile = "quick", cache, blender = "blender", colmap = "colmap";
  std::string blender_script, style;
  bool targets = false, allow_identity_mismatch = false, record_expected = false;
  int64_t seed = -1;
  bool no_colmap = false;
  int max_views = 0;
};

void print_summary(const capture::GenerateSummary& s) {
  std::printf("%-18s %3d views  render %7.1f s%s  weather %6.1f s  colmap %6.1f s  total %7.1f s  "
              "sparse %6d pts %.3f px  clean %6d pts %.3f px\n",
              (s.scene + "_" + s.variant).c_str(), s.views, s.render_s, s.cache_hit ? " (cached)" : "         ",
              s.weather_s, s.colmap_s, s.total_s, s.sparse.points, s.sparse.mean_reprojection_error_px,
              s.sparse_clean.points, s.sparse_clean.mean_reprojection_error_px);
  std::printf("%-18s identity %s (%s)\n", "", s.identity.substr(0, 16).c_str(), s.identity_check.c_str());
}

// The variants a command line asks for: --scene/--weather, or every variant of --suite.
std::vector<std::pair<capture::SceneSpec, std::string>> requested_variants(const GenerateArgs& a) {
  std::vector<std::pair<capture::SceneSpec, std::string>> out;
  if (a.suite.empty()) {
    if (!a.scene.empty()) out.emplace_back(capture::read_scene_spec(a.scene), a.weather);
    return out;
  }
  const JsonReader suite = JsonReader::from_file(a.suite);
  const JsonReader list = suite.child("variants");
  for (size_t i = 0; list.is_array() && i < list.size(); ++i)
    out.emplace_back(capture::read_scene_spec((fs::path(a.suite).parent_path() / list.at(i).get<std::string>("scene")).string()),
                     list.at(i).get<std::string>("weather"));
  return out;
}

// A flag no requested variant would read is refused before any rendering, naming it (docs/scenes.md,
// "Options that cannot take effect"): a dataset must be what its dataset.json says.
void refuse_unread(const GenerateArgs& a, const CLI::App& app) {
  auto given = [&](const char* flag) { return app.count(flag) > 0; };
  if (a.no_colmap && given("--colmap")) throw InputError("--colmap", "--no-colmap skips the SfM exports: COLMAP never runs");
  bool weather = false;
  for (const auto& [scene, name] : requested_variants(a)) {
    weather |= scene.variant(name).weather.is_object();
    const int views = scene.profile(a.profile).views;
    if (a.max_views >= views)
      throw InputError("--max-views", std::to_string(a.max_views) + " is not below the " + std::to_string(views) +
                                          " views of " + scene.name + "'s " + a.profile +
                                          " profile: every view would render (0: all)");
  }
  for (const char* flag : {"--seed", "--style", "--targets"})
    if (!weather && given(flag))
      throw InputError(flag, "sets the weather, and no requested variant has any (a clear variant)");
}

int run(const GenerateArgs& a, const CLI::App& app) {
  capture::GenerateOptions o;
  o.profile = a.profile;
  o.cache_dir = cache_dir(a.cache);
  if (a.seed >= 0) o.seed = uint64_t(a.seed);
  o.colmap = !a.no_colmap;
  o.targets = a.targets;
  o.allow_identity_mismatch = a.allow_identity_mismatch;
  o.record_expected = a.record_expected;
  if (a.allow_identity_mismatch && a.record_expected)
    throw InputError("--allow-identity-mismatch", "contradicts --record-expected, which writes the expected identity");
  if (!a.style.empty()) o.style = a.style == "paper" ? generator::WeatherStyle::kPaper : generator::WeatherStyle::kPhysical;
  o.blender.executable = a.blender;
  o.blender.max_views = a.max_views;
  o.blender.script = find_blender_script(a.blender_script);
  // The global -j/--threads caps Blender (and EEVEE's llvmpipe) and COLMAP too, not only our own
  // loops: the number in effect (all cores the process may use when -j is 0).
  o.blender.threads = num_threads();
  o.colmap_options.executable = a.colmap;
  o.colmap_options.num_threads = num_threads();
  if (!a.suite.empty()) {
    if (!a.scene.empty() || !a.weather.empty()) throw InputError("--suite", "use either --suite or --scene/--weather");
    refuse_unread(a, app);
    auto all = capture::generate_suite(a.suite, a.out, o);
    double total = 0;
    for (const auto& s : all) print_summary(s), total += s.total_s;
    std::printf("suite: %zu datasets in %s, %.1f s\n", all.size(), a.out.c_str(), total);
    return kExitOk;
  }
  if (a.scene.empty() || a.weather.empty()) throw InputError("--scene", "expected --scene FILE and --weather NAME, or --suite FILE");
  refuse_unread(a, app);
  print_summary(capture::generate_variant(a.scene, a.weather, a.out, o));
  return kExitOk;
}

Command make(CLI::App& root) {
  auto a = std::make_shared<GenerateArgs>();
  CLI::App* sub = root.add_subcommand(
      "generate",
      "Render a scene variant in Blender (cached), apply its weather and write a complete dataset with COLMAP "
      "exports (sparse/0 from the weather images, sparse_clean/0 from the clean ones, transforms.json). "
      "See docs/scenes.md.");
  sub->add_option("--scene", a->scene, "Scene spec (scenes/pool.json)");
  sub->add_option("--weather", a->weather, "Variant of the scene: snow, rain, ... or clear");
  sub->add_option("--suite", a->suite, "Suite file (scenes/suite.json): every variant into OUT/<scene>_<weather>");
  sub->add_option("--out", a->out, "Output dataset (or suite) directory")->required();
  sub->add_option("--profile", a->profile, "Render profile of the scene spec: tiny, quick, paper")->capture_default_str();
  sub->add_option("--cache", a->cache, "Cache of clean renders (default $WEATHERGS_CACHE or ~/.cache/weathergs)");
  sub->add_option("--seed", a->seed, "Weather seed (overrides the spec's; the cached render is reused)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--max-views", a->max_views, "Render only the first N views of the profile (0 = all; below the profile's count)")
      ->check(CLI::NonNegativeNumber);
  sub->add_flag("--no-colmap", a->no_colmap, "Skip the COLMAP exports (sparse/0, sparse_clean/0)");
  sub->add_flag("--targets", a->targets, "Write the weather's restoration targets (targets/, docs/generator.md)");
  sub->add_option("--style", a->style,
                  "Weather style of every variant: paper (the scene files' default) or physical (realism studies)")
      ->check(CLI::IsMember({"physical", "paper"}));
  sub->add_flag("--allow-identity-mismatch", a->allow_identity_mismatch,
                "Keep a dataset whose identity differs from the benchmark's expected one (scenes/expected/PROFILE.json); "
                "its dataset.json records the mismatch");
  sub->add_flag("--record-expected", a->record_expected,
                "Write each variant's identity into scenes/expected/PROFILE.json beside the scene file (changing the "
                "benchmark on purpose)");
  sub->add_option("--blender", a->blender, "Blender executable")->capture_default_str();
  sub->add_option("--blender-script", a->blender_script,
                  "Scene script (default: $WEATHERGS_BLENDER_SCRIPT, else the installed blender_scripts/render_scene.py)");
  sub->add_option("--colmap", a->colmap, "COLMAP executable")->capture_default_str();
  return {sub, [a, sub] { return run(*a, *sub); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(generate, weathergs::cli::make)
