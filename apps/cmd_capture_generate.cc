// `weathergs generate`: a scene variant or the whole benchmark suite, from scene spec to dataset.
#include <cstdio>
#include <memory>

#include "apps/command.h"
#include "core/error.h"
#include "apps/resources.h"
#include "core/parallel.h"
#include "capture/generate.h"

namespace weathergs::cli {
namespace {

struct GenerateArgs {
  std::string scene, weather, suite, out, profile = "quick", cache, blender = "blender", colmap = "colmap";
  std::string blender_script, style;
  bool targets = false;
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
}

int run(const GenerateArgs& a) {
  capture::GenerateOptions o;
  o.profile = a.profile;
  o.cache_dir = cache_dir(a.cache);
  if (a.seed >= 0) o.seed = uint64_t(a.seed);
  o.colmap = !a.no_colmap;
  o.targets = a.targets;
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
    auto all = capture::generate_suite(a.suite, a.out, o);
    double total = 0;
    for (const auto& s : all) print_summary(s), total += s.total_s;
    std::printf("suite: %zu datasets in %s, %.1f s\n", all.size(), a.out.c_str(), total);
    return kExitOk;
  }
  if (a.scene.empty() || a.weather.empty()) throw InputError("--scene", "expected --scene FILE and --weather NAME, or --suite FILE");
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
  sub->add_option("--seed", a->seed, "Weather seed (overrides the spec's; the cached render is reused)");
  sub->add_option("--max-views", a->max_views, "Render only the first N views of the profile (0 = all)")
      ->check(CLI::NonNegativeNumber);
  sub->add_flag("--no-colmap", a->no_colmap, "Skip the COLMAP exports (sparse/0, sparse_clean/0)");
  sub->add_flag("--targets", a->targets, "Write the weather's restoration targets (targets/, docs/generator.md)");
  sub->add_option("--style", a->style,
                  "Weather style of every variant: paper (the scene files' default) or physical (realism studies)")
      ->check(CLI::IsMember({"physical", "paper"}));
  sub->add_option("--blender", a->blender, "Blender executable")->capture_default_str();
  sub->add_option("--blender-script", a->blender_script,
                  "Scene script (default: $WEATHERGS_BLENDER_SCRIPT, else the installed blender_scripts/render_scene.py)");
  sub->add_option("--colmap", a->colmap, "COLMAP executable")->capture_default_str();
  return {sub, [a] { return run(*a); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(generate, weathergs::cli::make)
