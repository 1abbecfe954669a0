// The weather spec (DATASET_FORMAT.md, "Weather spec"), parsed strictly and resolved: every default
// filled in, so that dataset.json records exactly what was simulated. Parameter tables with
// defaults and units: docs/generator.md.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>

#include "core/camera.h"
#include "core/json_reader.h"
#include "generator/lens/lens_spec.h"
#include "generator/particles.h"
#include "generator/render.h"

namespace weathergs {

// The spec's "camera" block: where given, overrides every view's value.
struct CameraOverrides {
  std::optional<double> exposure_s, f_number, focal_length_mm, focus_distance_m;
  Camera apply(Camera camera) const;
};

struct ParticleEffectSpec {
  SpeciesOptions species;
  ParticleAppearance appearance;
};

struct FogSpec {
  enum class Source { kVisibility, kBeta, kFromRain };
  Source source = Source::kVisibility;
  double visibility_m = 0;   // kVisibility
  double beta_per_m = 0;     // resolved extinction coefficient (all sources)
  std::optional<Eigen::Vector3f> airlight;  // linear RGB; absent: estimated from the clean images
};

struct WeatherSpec {
  uint64_t seed = 0;
  CameraOverrides camera;
  RenderOptions render;
  std::optional<ParticleEffectSpec> rain, snow;
  std::optional<FogSpec> fog;
  // Lens droplets (effects.lens_droplets), parsed by generator/lens (docs/lens_droplets.md);
  // run_weather resolves the window pose against the first camera.
  std::optional<lens::LensDropletSpec> lens_droplets;

  // "rain", "snow+fog", ... ("clear" when no effect is given).
  std::string weather_name() const;
  Json to_json() const;  // the resolved spec
};

// Strict: unknown keys, wrong types and out-of-range values are InputError with file and pointer.
WeatherSpec parse_weather_spec(const JsonReader& spec);

}  // namespace weathergs
