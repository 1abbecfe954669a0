// `weathergs weather`: adds rain, snow and fog (physical units, or the paper's style) to a clean dataset.
#include <cstdio>
#include <memory>

#include "apps/command.h"
#include "core/json_reader.h"
#include "core/progress.h"
#include "generator/weather.h"

namespace weathergs::cli {
namespace {

struct WeatherArgs {
  std::string in, spec, out, name;
  int64_t seed = -1;
  bool no_layers = false, no_manifest = false, targets = false;
  std::string style;
  double mask_threshold = generator::WeatherRunOptions().mask_threshold;
};

Command make_weather(CLI::App& root) {
  auto a = std::make_shared<WeatherArgs>();
  CLI::App* sub = root.add_subcommand(
      "weather",
      "Render rain, snow and fog (weather spec, docs/formats.md) into a clean dataset with depth. "
      "Writes images/, clean/, depth/, masks/particles/, layers/ (float alpha, fog transmittance, "
      "per-particle manifests) and dataset.json with the resolved spec, seed and stage timings. "
      "See docs/generator.md.");
  sub->add_option("--in", a->in, "Clean dataset (clean/ or images/, depth/, cameras.json)")->required();
  sub->add_option("--spec", a->spec, "Weather spec JSON")->required();
  sub->add_option("--out", a->out, "Output dataset directory (replaced atomically)")->required();
  sub->add_option("--seed", a->seed, "Override the spec's seed")->check(CLI::NonNegativeNumber);
  sub->add_option("--name", a->name, "Dataset name (default: <clean name>_<weather>)");
  sub->add_option("--mask-threshold", a->mask_threshold,
                  "Particle alpha at or above which masks/particles is set")
      ->capture_default_str();
  sub->add_flag("--no-layers", a->no_layers, "Do not write float layers (layers/*.exr)");
  sub->add_flag("--no-manifest", a->no_manifest, "Do not write per-particle manifests");
  sub->add_flag("--targets", a->targets,
                "Also write targets/no_particles/ (every effect but the particles) and targets/lens_only/ "
                "(the clean view with the lens drops only): exact targets for restoration filters");
  sub->add_option("--style", a->style, "Override the spec's style: physical (ignores paper blocks) or paper")
      ->check(CLI::IsMember({"physical", "paper"}));
  return {sub, [a] {
            generator::WeatherRunOptions o;
            if (a->seed >= 0) o.seed = uint64_t(a->seed);
            o.name = a->name;
            o.write_layers = !a->no_layers;
            o.write_manifest = !a->no_manifest;
            o.mask_threshold = a->mask_threshold;
            o.write_targets = a->targets;
            if (!a->style.empty()) o.style = a->style == "paper" ? generator::WeatherStyle::kPaper : generator::WeatherStyle::kPhysical;
            const Json block = generator::run_weather(a->in, JsonReader::from_file(a->spec), a->out, o);
            if (!is_quiet()) {
              std::fprintf(stderr, "wrote %s (seed %s):", a->out.c_str(), block["seed"].dump().c_str());
              for (const Json& s : block["stages"])
                std::fprintf(stderr, " %s %.2fs", s["name"].get<std::string>().c_str(), s["seconds"].get<double>());
              std::fprintf(stderr, "\n");
            }
            return kExitOk;
          }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(weather, weathergs::cli::make_weather)
