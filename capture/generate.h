// `weathergs generate`: one scene variant or a whole suite, from scene spec to complete dataset:
//   1. clean render of the variant (surface state, lights) in Blender, cached by a hash of the job,
//      together with its oracle COLMAP model (known poses, clean images);
//   2. the weather pass (generator/weather.h: particles, fog, lens droplets) on the clean render;
//   3. exports: sparse/0 (COLMAP point_triangulator on the *weather* images with the known poses),
//      sparse_clean/0 (the same on the clean images), transforms.json.
// Re-running with another weather seed reuses the cached render.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "capture/blender.h"
#include "capture/colmap.h"
#include "capture/expected_identity.h"
#include "generator/weather_spec.h"

namespace weathergs::capture {

struct GenerateOptions {
  std::string profile = "quick";
  // Where clean renders are cached ("<cache_dir>/clean/<sha256 of the job>"); required (the
  // `weathergs` binary defaults it to $WEATHERGS_CACHE or ~/.cache/weathergs, apps/resources.h).
  std::string cache_dir;
  std::optional<uint64_t> seed;  // overrides the variant's weather seed
  bool colmap = true;            // sparse/0 and sparse_clean/0 exports
  bool targets = false;          // the weather's restoration targets (targets/, docs/generator.md)
  std::optional<generator::WeatherStyle> style;  // overrides the variants' weather style (physical or paper)
  // The expected identities (scenes/expected/<profile>.json beside the scene file): a variant made
  // with the settings of an entry must reproduce its identity, else generate fails (exit 2) naming
  // the first differing file; allow_identity_mismatch keeps such a dataset, recording the mismatch in
  // its dataset.json. record_expected writes the variant's identity into that file instead (for
  // whoever changes the benchmark on purpose).
  bool allow_identity_mismatch = false;
  bool record_expected = false;
  BlenderOptions blender;
  ColmapOptions colmap_options;

  void validate() const;  // InputError naming the field (profile, cache_dir set; blender, colmap options)
};

struct GenerateSummary {
  std::string scene, variant, out_dir, cache_entry;
  bool cache_hit = false;
  int views = 0;
  double render_s = 0, weather_s = 0, colmap_s = 0, total_s = 0;
  ModelStats sparse, sparse_clean;
  std::string identity;        // the dataset's identity (sha256)
  std::string identity_check;  // "matches", "recorded", "mismatch allowed", "no expected identity", ...
  Json to_json() const;
};

// The cache entry of a variant's clean render (rendered now if absent).
std::string ensure_clean_render(const SceneSpec& scene, const std::string& variant, const GenerateOptions& options,
                                bool* cache_hit = nullptr, double* seconds = nullptr);

// Writes the dataset of scene_path/variant at out_dir atomically.
GenerateSummary generate_variant(const std::string& scene_path, const std::string& variant, const std::string& out_dir,
                                 const GenerateOptions& options);

// A suite file: {"name", "description", "variants": [{"scene": "pool.json" (relative to the suite
// file), "weather": "rain"}, ...]}. Writes <out_dir>/<scene>_<weather>/ for each and
// <out_dir>/summary.json; out_dir is created if needed. A failing variant stops the suite (the
// datasets finished before it stay).
std::vector<GenerateSummary> generate_suite(const std::string& suite_path, const std::string& out_dir,
                                            const GenerateOptions& options);

}  // namespace weathergs::capture
