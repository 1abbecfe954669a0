// `weathergs weather` as a library call: clean dataset + weather spec -> weathered dataset.
//
//   WeatherRunOptions options;                    // defaults documented below
//   Json block = run_weather("clean/", JsonReader::from_file("weather.json"), "out/", options);
//
// Input: a dataset (docs/formats.md) with clean images in clean/ (or images/) as PNG, planar depth
// in depth/<view>.exr, and cameras with time_s and exposure_s. Output (written atomically through an
// AtomicDirectory; a failed run leaves nothing at out_dir):
//   images/<view>.png           the weathered views (8-bit sRGB)
//   clean/<view>.png            the clean views, copied
//   depth/<view>.exr            copied; sparse/ and transforms.json copied when present (copy_exports)
//   masks/particles/<view>.png  particle alpha >= mask_threshold (when a particle effect ran)
//   targets/no_particles/<view>.png, targets/lens_only/<view>.png   with write_targets: the view with
//                               every stage but the particle ones, and the clean view with the lens only
//   layers/particle_alpha/<view>.exr, layers/<species>_alpha/<view>.exr, layers/fog_transmittance/
//   layers/particles_<species>/<view>.csv   the per-particle manifest (docs/generator.md)
//   cameras.json                the cameras with the spec's camera overrides applied
//   dataset.json                splits copied; generator = the input's block (if any) plus the
//                               weather's entries (the returned block)
// Every output but the measured seconds in dataset.json is byte-identical for the same inputs and
// seed, whatever the thread count or view order.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/json_reader.h"
#include "generator/weather_spec.h"

namespace weathergs::generator {

struct WeatherRunOptions {
  std::optional<uint64_t> seed;          // overrides the spec's seed (e.g. one seed per scene variant)
  std::string name;                      // dataset name; empty: "<clean name>_<weather>"
  std::vector<std::string> view_order;   // processing order (a permutation of the views); empty:
                                         // cameras.json order. Outputs do not depend on it.
  bool write_layers = true;              // layers/*.exr (float alpha, fog transmittance)
  bool write_manifest = true;            // layers/particles_<species>/<view>.csv
  double mask_threshold = 0.02;          // masks/particles: particle alpha >= this, in (0, 1]
  bool write_targets = false;            // targets/no_particles and targets/lens_only (docs/generator.md)
  std::optional<WeatherStyle> style;     // overrides the spec's "style" (physical ignores paper blocks)
  bool copy_exports = true;              // copy the input's sparse/ and transforms.json (false when the
                                         // caller writes its own, as capture's generate does)

  void validate() const;  // InputError naming the field
};

// Reads the clean dataset, applies the spec, writes a complete dataset at out_dir atomically
// (AtomicDirectory), returns the "generator" block written to dataset.json: the input dataset's
// block (entries of earlier stages, e.g. capture's render) plus the weather's own entries
//   {"version", "seed", "spec" (resolved, every default filled in), "stages": [... earlier stages,
//    {"name", "seconds"} per weather stage], "sky_radiance": [r, g, b], "counters": {...}, "outputs": {...}}.
// The spec may be part of a larger document: errors name spec.file() and spec.pointer().
Json run_weather(const std::string& clean_dataset_dir, const JsonReader& spec, const std::string& out_dir,
                 const WeatherRunOptions& options);

// Sky radiance estimate of a clean linear RGB image: the mean of its brightest 0.5% pixels (by
// luminance). run_weather averages it over all views in cameras.json order.
std::array<double, 3> estimate_sky_radiance(const Image& clean_linear);
// The dataset-wide sky radiance: the mean of the views' estimates, summed in the given order.
Eigen::Vector3f mean_sky_radiance(const std::vector<std::array<double, 3>>& per_view);

}  // namespace weathergs::generator
