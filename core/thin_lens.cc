#include "core/thin_lens.h"

#include <cmath>
#include <sstream>

#include "core/error.h"

namespace weathergs {

double ThinLens::coc_diameter_px(double fx, double z_m) const {
  if (!(z_m > 0)) return 0;
  return fx * aperture_m * std::abs(z_m - focus_m) / (z_m * (focus_m - focal_length_m));
}

std::string ThinLens::to_string() const {
  std::ostringstream s;
  s << "ThinLens{focal_length_m " << focal_length_m << ", aperture_m " << aperture_m << ", focus_m " << focus_m << "}";
  return s.str();
}

std::optional<ThinLens> thin_lens_of(const Camera& c) {
  if (!c.f_number || !c.focal_length_mm || !c.focus_distance_m) return std::nullopt;
  const std::string where = "view '" + c.name + "'";
  const double n = *c.f_number, f_mm = *c.focal_length_mm, s = *c.focus_distance_m;
  if (!(std::isfinite(n) && n > 0)) throw InputError(where, "f_number must be a positive number, got " + std::to_string(n));
  if (!(std::isfinite(f_mm) && f_mm > 0))
    throw InputError(where, "focal_length_mm must be a positive number, got " + std::to_string(f_mm));
  ThinLens lens;
  lens.focal_length_m = f_mm / 1000.0;
  lens.aperture_m = lens.focal_length_m / n;
  lens.focus_m = s;
  if (!(std::isfinite(s) && s > lens.focal_length_m))
    throw InputError(where, "focus_distance_m must be finite and exceed the focal length (" +
                                std::to_string(lens.focal_length_m) + " m), got " + std::to_string(s));
  return lens;
}

}  // namespace weathergs
