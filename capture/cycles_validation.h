// Path-tracer validation of the weather compositor (benchmarks/README.md, "Path-tracer validation").
//
// Lens drops (a dataset whose spec has lens_droplets alone, attached to the lens, untilted, on the
// scene side): the view's drops from dataset.json go to Blender as water caps closed by their base on
// a cover-glass slab (glass_thickness_m; both parented to the camera), in front of the camera's dark
// body (camera_body), with the camera's depth of field when the effect defocuses; the Cycles layers
// are divided by the glass's transmission (a render without it: the dataset's clean view is seen
// through the glass); the C++ layer is
// images - clean (the drops change far more than an 8-bit level). Particles: a dataset made by
// `weathergs generate` or `weathergs weather` with rain and/or snow only, with the generator's
// particle manifests and float layers: the view's particles (position at shutter open,
// velocity, visual diameter) go to Blender as water spheres (rain) or Lambertian flakes of the spec's
// albedo and opacity (snow), moving linearly over the exposure; Cycles renders the variant's scene with
// and without them (same sampling seed, so the noise of paths that miss every particle cancels), with
// motion blur, float output, and depth of field when the generator defocuses. A third and fourth
// render repeat the pair with another seed: the reference's own noise floor. The weather layers
// weathered - clean (linear RGB, float on both sides) are compared. A fifth render gives the
// particles' coverage alone (opaque emitters, the scene a holdout): the streaks' extent is measured
// on it against the generator's alpha layers, as well as on the layers themselves.
#pragma once

#include <string>

#include "core/json_reader.h"
#include "generator/lens/optics.h"

namespace weathergs::capture {

constexpr int kCoverageSampleFactor = 8;

struct CyclesValidationOptions {
  std::string dataset;            // required
  std::string view = "001";
  int samples = 256;              // Cycles samples per pixel
  int nearest = 20;               // particles whose streak extents are compared
  // Samples of the coverage view alone (0: kCoverageSampleFactor x samples). A streak's coverage is
  // a few thousandths per pixel, so its relative Monte Carlo noise per pixel is ~sqrt(1 / (p N)):
  // 57 % at 1024 samples, 20 % at 8192, and the noise, not the renderer, then decides the measured
  // streak ends (benchmarks/README.md). The view holds only the particles, so it is cheap.
  int coverage_samples = 0;
  std::string out_dir = "cycles_validation";  // job, Blender log, renders, result.json
  std::string blender = "blender";
  std::string blender_script;     // blender_scripts/render_scene.py (required)
  std::string scene_spec;         // default: the dataset's generator.scene_spec (relative to the cwd)
  // Particles: Cycles renders this dataset's particles instead (the same weather, spec and seed, drawn
  // with a lower visibility_cutoff or near_m: a superset of `dataset`'s, checked by particle id), so
  // the comparison includes the light the generator's cutoffs leave out. Empty: `dataset` itself.
  std::string reference_dataset;
  bool reuse_renders = false;     // keep out_dir's Cycles renders when they were made from the same job
  // Lens drops: the cover glass they sit on, modelled in the reference as a slab on the camera side
  // of the drops (the generator's `glass_thickness_mm`: a slab, or 0 for its thin glass, which turns
  // no ray). 1 mm of crown glass is our choice of a typical cover (the physical style's default too);
  // 0 leaves the plate out, the counterpart of the generator's thin glass.
  double glass_thickness_m = 1e-3;
  double glass_refractive_index = generator::lens::kCrownGlassRefractiveIndex;
  // Lens drops: a dark camera front 1 mm behind the aperture, so light the drops or the glass send back
  // towards the camera meets the camera (as on a real one), not the sky behind an invisible camera.
  bool camera_body = true;
  void validate() const;          // InputError naming the field
};

// Runs Cycles and compares; returns (and writes to out_dir/result.json) the figures:
// psnr_weather_layer[_box4]_db, psnr_no_weather_baseline[_box4]_db, psnr_cycles_seed_vs_seed[_box4]_db,
// gain_over_no_weather_box4_db, changed_fraction_{cycles,cpp} and changed_iou (where the 4x4-averaged
// layers change the view by more than 0.02, and the IoU of those regions), energy_box4_{cycles,cpp}
// (RMS of the 4x4-averaged layer; Cycles' with its noise variance removed),
// energy_ratio_cpp_over_cycles, mean_layer_{cycles,cpp}, streak_end_error_{median,max}_px over
// `streaks` (10%/90% quantiles of each streak's |layer| along its projected path; the nearest
// `nearest` particles with both ends in the image and at most half of each tenth of their capsule
// under other particles' streaks), coverage_streak_end_error_{median,max}_px (the same quantiles of
// the coverage: Cycles' coverage render, with cycles_coverage_samples, against 1 - prod(1 - alpha) of
// the generator's alpha layers; null when one side shows nothing of a streak), the seconds of both
// renderers and their ratio. Lens drops: no streak figures; glass_plate_mm, glass_transmission and
// camera_body record the reference's glass and body.
Json validate_against_cycles(const CyclesValidationOptions& options);

}  // namespace weathergs::capture
