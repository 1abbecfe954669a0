// The weather spec (docs/formats.md, "Weather spec"), parsed strictly and resolved: every default
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
#include "generator/overlay.h"
#include "generator/particles.h"
#include "generator/render.h"

namespace weathergs::generator {

// The spec's "camera" block: where given, overrides every view's value.
struct CameraOverrides {
  std::optional<double> exposure_s, f_number, focal_length_mm, focus_distance_m;
  Camera apply(Camera camera) const;
};

// Named intensities of an effect (physics_constants.h: the class bounds and their sources).
enum class Intensity { kLight, kModerate, kHeavy, kViolent };
const char* to_string(Intensity i);
// The rain rate or snow water-equivalent rate (mm/h) a named intensity stands for.
double intensity_rate_mm_h(Species species, Intensity intensity);

// "physical": every particle as physics makes it (the default). "paper": WeatherGS's benchmark look,
// exaggerated on purpose: larger, denser, more opaque particles on the same world-space state (so
// they stay multi-view consistent) plus the per-view 2D overlay (not consistent, as in the paper).
// docs/generator.md, "Styles", lists every exaggeration and its default.
enum class WeatherStyle { kPhysical, kPaper };
const char* to_string(WeatherStyle style);

struct ParticleEffectSpec {
  SpeciesOptions species;
  ParticleAppearance appearance;
  std::optional<Intensity> intensity;     // set when the spec named an intensity instead of rate_mm_h
  std::optional<OverlayOptions> overlay;  // paper style: the per-view 2D layer
  // This species' render.visibility_cutoff when set (the effect's "visibility_cutoff"); the physical
  // style gives snow kPhysicalSnowVisibilityCutoff unless the spec sets a cutoff (docs/generator.md).
  std::optional<double> visibility_cutoff;
  RenderOptions render_for(const RenderOptions& render) const {
    RenderOptions r = render;
    if (visibility_cutoff) r.visibility_cutoff = *visibility_cutoff;
    return r;
  }
};

// Physical snow's visibility cutoff: against Cycles rendering every flake of the view (down to a
// peak alpha of 0.002), the layer drawn at 0.01 is +5.8 dB closer than an empty one with 0.65 of the
// energy (both aims missed: the faint flakes carry a third of it); at 0.002, +11.3 dB and 0.94
// (docs/record/cycles_validation.md, "Snow against its whole population"). Rain keeps render.visibility_cutoff
// (0.01): drawing fainter drops brought it no closer (its far drops are lit by what surrounds them).
constexpr double kPhysicalSnowVisibilityCutoff = 0.002;

struct FogSpec {
  enum class Source { kVisibility, kBeta, kFromRain };
  Source source = Source::kVisibility;
  double visibility_m = 0;   // kVisibility
  double beta_per_m = 0;     // resolved extinction coefficient (all sources)
  std::optional<Eigen::Vector3f> airlight;  // linear RGB; absent: estimated from the clean images
};

struct WeatherSpec {
  uint64_t seed = 0;
  WeatherStyle style = WeatherStyle::kPhysical;
  CameraOverrides camera;
  RenderOptions render;
  std::optional<ParticleEffectSpec> rain, snow;
  std::optional<FogSpec> fog;
  // lighting.sun: the scene's sun, lighting the particles (generate fills it from the scene's lights).
  std::optional<SunLight> sun;
  // Lens droplets (effects.lens_droplets), parsed by generator/lens (docs/lens_droplets.md);
  // run_weather resolves the window pose against the first camera.
  std::optional<lens::LensDropletSpec> lens_droplets;

  // "rain", "snow+fog", ... ("clear" when no effect is given).
  std::string weather_name() const;
  Json to_json() const;  // the resolved spec
};

// Strict: unknown keys, wrong types and out-of-range values are InputError with file and pointer.
// `style_override` replaces the spec's "style"; overriding a paper spec with physical ignores its
// "paper" blocks (that is what the override is for: the same scene variants in both styles).
WeatherSpec parse_weather_spec(const JsonReader& spec, std::optional<WeatherStyle> style_override = std::nullopt);

}  // namespace weathergs::generator
