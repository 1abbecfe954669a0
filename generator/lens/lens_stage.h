// Lens droplets as the last stage of `weathergs weather` (generator/stages.h): the drops on the
// glass see the scene after fog, rain and snow, so the airborne effects appear (inverted) inside
// the drops and the drops are never hidden behind particles.
//
// Per view the stage replaces view.radiance with the composited image and leaves:
//   view.layers[layout::kLensCoverageLayer] ("lens_coverage")  float coverage in [0, 1]  -> layers/lens_coverage/<view>.exr
//   view.lens_mask                {0, 1}                     -> masks/lens/<view>.png
//   view.lens_drops               the per-view drop list     -> dataset.json generator.lens_droplets
#pragma once

#include <cstdint>
#include <string>

#include "generator/lens/lens_render.h"
#include "generator/stages.h"

namespace weathergs::generator::lens {

class LensDropletStage : public WeatherStage {
 public:
  // `spec` resolved against `reference` (the dataset's first camera in cameras.json order).
  LensDropletStage(const LensDropletSpec& spec, uint64_t seed, const Camera& reference)
      : renderer_(spec, seed, reference) {}
  std::string name() const override { return "lens_droplets"; }
  StageKind kind() const override { return StageKind::kLens; }
  // The drops are placed at the view's shutter-open time (camera.time_s).
  void run(WeatherView& view) const override;

 private:
  LensDropletRenderer renderer_;
};

}  // namespace weathergs::generator::lens
