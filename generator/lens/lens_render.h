// Lens droplets for one view: the public entry point of generator/lens/.
//
//   LensDropletSpec spec = resolve_lens_droplet_spec(parse_lens_droplet_spec(reader), cameras[0]);
//   LensDropletRenderer renderer(spec, seed, cameras[0]);   // samples drops; Embree only if any
//   LensViewResult r = renderer.render(image_linear, camera, camera.time_s);
//
// Per pixel, samples_per_pixel stratified camera rays (seeded on view name and pixel) are traced
// through the drops (drop_scene.h). The light that came through water forms a premultiplied
// droplet layer and a coverage layer; both are blurred with the thin-lens circle of confusion of
// the glass (the camera focuses on the scene) and composited over the input:
//   out = blur(droplet radiance * coverage) + (1 - blur(coverage)) * input.
#pragma once

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "core/camera.h"
#include "core/image.h"
#include "core/json_reader.h"
#include "generator/lens/drop_scene.h"
#include "generator/lens/drops.h"
#include "generator/lens/lens_spec.h"

namespace weathergs::generator::lens {

struct LensViewResult {
  Image image;     // composited linear RGB, the input's size
  Image coverage;  // 1 channel, [0, 1]: fraction of the pixel's light that came through water
  Image mask;      // 1 channel, {0, 1}: coverage >= spec.mask_threshold
  Json drops;      // {"view", "time_s", "blur_diameter_px", "drops": [...]} (docs/lens_droplets.md)
  int64_t camera_rays = 0;   // camera rays traced (pixels near no drop are not traced)
  int64_t water_rays = 0;    // of which touched water
  int64_t embree_rays = 0;   // Embree ray casts, all path segments
  double trace_seconds = 0, blur_seconds = 0;
  double blur_diameter_px = 0;
};

// Largest blur diameter applied (pixels): beyond it the glass is a uniform veil anyway and the
// kernel cost grows quadratically; recorded in the per-view JSON when it clips.
constexpr double kMaxBlurDiameterPx = 256;

// Disk blur (normalized, anti-aliased disk of the given diameter, zero outside the layer) of a
// float cv::Mat with any channel count. Diameters above full_resolution_max_px are computed at 1/k
// resolution, k = floor(diameter / full_resolution_max_px) (box average down, bilinear up): the
// result is then a disk convolved with a k-px box and tent, k / diameter <= 1/full_resolution_max_px
// wider, at a cost independent of the diameter. The layer mean is kept either way.
constexpr double kDiskBlurFullResolutionMaxPx = 32;
cv::Mat disk_blur(const cv::Mat& layer, double diameter_px,
                  double full_resolution_max_px = kDiskBlurFullResolutionMaxPx);

class LensDropletRenderer {
 public:
  // `spec` must be resolved (resolve_lens_droplet_spec). The reference camera (the dataset's first
  // view in cameras.json order, whatever order views are rendered in) sets the lens-attach sampling
  // region. Creates the Embree device only when spec.count > 0.
  LensDropletRenderer(const LensDropletSpec& spec, uint64_t seed, const Camera& reference_camera);

  // `image`: the view's linear RGB radiance (clean, or after the airborne effects). Thread-safe.
  // sky: the dataset's sky radiance estimate, required when the spec's environment is "sky".
  LensViewResult render(const Image& image, const Camera& camera, double time_s,
                        const Eigen::Vector3f* sky = nullptr) const;

  const LensDropletSpec& spec() const { return spec_; }
  const DropField& field() const { return field_; }
  bool has_embree_device() const { return device_ != nullptr; }

 private:
  LensDropletSpec spec_;
  uint64_t seed_;
  DropField field_;
  std::unique_ptr<EmbreeDevice> device_;
};

// Stable 64-bit FNV-1a hash (view names key the per-pixel random streams).
uint64_t fnv1a64(const std::string& s);

}  // namespace weathergs::generator::lens
