// The paper style's dense 2D weather layer (docs/generator.md, "Styles").
//
// WeatherGS's benchmark added, after the Blender render, a dense OpenCV layer of streaks (rain) or
// flakes (snow) to every image "to achieve a denser weather effect". We offer the same as an explicit,
// documented option: elements drawn in image space, keyed on (seed, species, view name), so the layer
// is NOT multi-view consistent, exactly as in the paper. It is part of the particle layer: it adds to
// particle_alpha and masks/particles and is absent from the no-particle target. The stage that
// composites it is OverlayStage (generator/stages.h).
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "core/image.h"
#include "core/json_reader.h"
#include "generator/particles.h"

namespace weathergs::generator {

// Sizes are in pixels of a 600-pixel-wide image (the paper profile) and scale with the image width,
// so every profile looks alike. Every default is written into dataset.json's resolved spec.
struct OverlayOptions {
  Species species = Species::kRain;
  // Elements per megapixel at the reference (named "heavy") rate; scaled linearly by rate_scale.
  double count_per_mpx = 0;
  double rate_scale = 1.0;                    // resolved: rate / heavy rate of the species
  std::array<double, 2> length_px = {18, 45};  // rain: streak length range
  double width_px = 1.5;                       // rain: streak width
  double angle_deg = 8;                        // rain: mean streak angle from vertical (+ leans right)
  double angle_jitter_deg = 4;                 // rain: uniform jitter around the mean
  std::array<double, 2> radius_px = {1.0, 3.5};  // snow: flake radius range (log-uniform)
  std::array<double, 2> opacity = {0.25, 0.6};   // peak alpha range of an element (uniform)
  double brightness = 1.0;                     // element radiance = brightness x the sky radiance
  double blur_sigma_px = 0.6;                  // Gaussian blur of the layer (soft edges)

  static OverlayOptions defaults(Species species);  // the documented paper-style defaults
  void validate(const std::string& where) const;
  static OverlayOptions from_json(const JsonReader& r, OverlayOptions defaults);  // strict
  Json to_json() const;
};

// The layer of one view: alpha (1 channel) of the elements, after the blur. Deterministic for
// (options, seed, view name), whatever the thread count.
Image render_overlay_alpha(const OverlayOptions& options, uint64_t seed, const std::string& view_name, int width,
                           int height);

}  // namespace weathergs::generator
