// The thin-lens model of a camera with lens data (cameras.json's optional f_number,
// focal_length_mm, focus_distance_m): the one place the circle of confusion is computed.
#pragma once

#include <optional>
#include <string>

#include "core/camera.h"

namespace weathergs {

// All lengths in meters. aperture_m is the entrance-pupil diameter f / N.
struct ThinLens {
  double focal_length_m = 0, aperture_m = 0, focus_m = 0;

  // Circle-of-confusion *diameter* on the sensor, in pixels (fx pixels per unit of normalized image
  // plane), of a point at planar depth z_m: fx * A * |z - s| / (z * (s - f)) (e.g. Potmesil & Chakravarty
  // 1981; the sensor-plane blur A f |z - s| / (z (s - f)) divided by f). 0 for z <= 0.
  double coc_diameter_px(double fx, double z_m) const;
  double coc_radius_px(double fx, double z_m) const { return 0.5 * coc_diameter_px(fx, z_m); }
  std::string to_string() const;
};

// The camera's thin lens when it has all three lens fields; nullopt when any is absent. Throws
// InputError naming the view when they are present but not a physical lens (N, f not positive and
// finite, focus distance not finite or not beyond the focal length).
std::optional<ThinLens> thin_lens_of(const Camera& camera);

}  // namespace weathergs
