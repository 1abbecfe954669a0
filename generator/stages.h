// The weather pipeline as a list of stages. Each stage transforms one view's linear radiance in
// place; run_weather (generator/weather.h) runs them in order on every view, times them, and records
// them in dataset.json's generator.stages. Order: fog, rain, snow, then lens droplets
// (generator/lens/lens_stage.h, appended last: it sees the weathered scene through the drops).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "core/camera.h"
#include "core/image.h"
#include "core/json_reader.h"
#include "generator/particles.h"
#include "generator/render.h"
#include "generator/weather_spec.h"

namespace weathergs::generator {

// One view passing through the stages.
struct WeatherView {
  // Starts with radiance = clean and zero particle alpha; every other member default-initialized.
  WeatherView(const Camera& camera_, const Image& clean_, const Image& depth_, const EnvironmentLight& environment_)
      : camera(camera_), clean(clean_), depth(depth_), environment(environment_), radiance(clean_),
        particle_alpha(camera_.width, camera_.height, 1, ColorSpace::kLinear) {}

  const Camera& camera;          // spec overrides applied
  const Image& clean;            // linear RGB
  const Image& depth;            // planar z, 1 channel
  const EnvironmentLight& environment;
  Image radiance;                // linear RGB; starts as the clean image
  Image particle_alpha;          // 1 channel: 1 - prod(1 - A_stage) over the particle stages
  bool has_particles = false;    // a particle stage ran (masks/particles is written)
  FogState fog;                  // set by the fog stage for later stages
  std::map<std::string, Image> layers;       // float layers: layers/<name>/<view>.exr
  std::map<std::string, std::string> texts;  // text layers: layers/<name>/<view>.csv
  std::map<std::string, int64_t> counters;   // summed over views into generator.stage_counters
  std::optional<Image> lens_mask;            // set by the lens stage: masks/lens/<view>.png
  Json lens_drops;                           // set by the lens stage: generator.lens_droplets.views
};

// What a stage adds: the restoration targets (docs/generator.md) re-run the stages without the
// particle ones (no-particle target) or with the lens ones only (lens-only target).
enum class StageKind { kFog, kParticles, kLens };

class WeatherStage {
 public:
  virtual ~WeatherStage() = default;
  virtual std::string name() const = 0;
  virtual StageKind kind() const = 0;
  // Called concurrently for different views: must not modify the stage.
  virtual void run(WeatherView& view) const = 0;
};

// Fog: transmittance t = exp(-beta * ray length) from the clean depth (background: t = 0);
// radiance = radiance * t + airlight * (1 - t). Writes layers/fog_transmittance.
class FogStage : public WeatherStage {
 public:
  FogStage(double beta_per_m, const Eigen::Vector3f& airlight) : beta_(beta_per_m), airlight_(airlight) {}
  std::string name() const override { return "fog"; }
  StageKind kind() const override { return StageKind::kFog; }
  void run(WeatherView& view) const override;

 private:
  double beta_;
  Eigen::Vector3f airlight_;
};

// Rain or snow: the world-space particle field rendered into the view (docs/generator.md).
// Writes layers/<species>_alpha and the manifest layers/particles_<species>/<view>.csv.
class ParticleStage : public WeatherStage {
 public:
  // sun: lights the particles with the optics shading (lighting.sun of the spec), when given.
  ParticleStage(const ParticleEffectSpec& effect, const RenderOptions& render, uint64_t seed, bool manifest,
                std::optional<SunLight> sun = std::nullopt);
  std::string name() const override { return to_string(field_.options().species); }
  StageKind kind() const override { return StageKind::kParticles; }
  void run(WeatherView& view) const override;
  const ParticleField& field() const { return field_; }

 private:
  ParticleField field_;
  ParticleAppearance appearance_;
  RenderOptions render_;
  bool manifest_;
  std::optional<SunLight> sun_;
};

// The paper style's per-view 2D layer (generator/overlay.h): radiance = (1 - A) radiance +
// A (brightness x sky); adds A into particle_alpha and writes layers/<species>_overlay_alpha.
class OverlayStage : public WeatherStage {
 public:
  OverlayStage(const OverlayOptions& options, uint64_t seed) : options_(options), seed_(seed) {}
  std::string name() const override { return std::string(to_string(options_.species)) + "_overlay"; }
  StageKind kind() const override { return StageKind::kParticles; }
  void run(WeatherView& view) const override;

 private:
  OverlayOptions options_;
  uint64_t seed_;
};

// Cells of class k of the field that can hold a particle visible in the view (frustum from near_m
// to distance_m, dilated by the motion over the exposure and by extra_margin_m, e.g. the largest
// defocus blur in world units), in a fixed order.
std::vector<CellIndex> visible_cells(const ParticleField& field, int k, const Camera& camera,
                                     double near_m, double distance_m, double extra_margin_m = 0);

// Bound on a particle's speed relative to its class frame: fall-speed spread of the class, gusts
// at 3 standard deviations per component, flutter.
double relative_speed_bound_m_s(const ParticleField& field, int k);

// How far class k is populated in a view: visibility_distance_m (a still particle), shortened by
// motion blur where every particle of the class must move across the image during the exposure
// (its streak spreads its mass below the cutoff beyond this distance; docs/generator.md).
double population_distance_m(const ParticleField& field, int k, const RenderView& view, double opacity,
                             const RenderOptions& options);

// The manifest's CSV header (one row per drawn particle).
extern const char* const kManifestHeader;

}  // namespace weathergs::generator
