// Microphysics of rain and snow: size distributions, fall speeds, shapes and optical extinction,
// each a direct transcription of a published law (constants in generator/physics_constants.h).
// Units: diameters in mm, rates in mm/h (snow: water equivalent), speeds in m/s.
#pragma once

#include <functional>
#include <string>

namespace weathergs::generator::physics {

// Marshall-Palmer raindrop size distribution: N(D) = 8000 exp(-Lambda D) m^-3 mm^-1.
double marshall_palmer_lambda_per_mm(double rate_mm_h);  // 4.1 R^-0.21; rate_mm_h > 0
// Atlas et al. (1973) terminal velocity of a raindrop of (equal-volume) diameter D, clamped at 0.
double atlas_velocity_m_s(double diameter_mm);
// Beard-Chuang equilibrium axis ratio b/a (vertical over horizontal), clamped at 1 (small drops
// are spheres); the polynomial's value at 9 mm beyond it.
double beard_chuang_axis_ratio(double diameter_mm);

// Gunn-Marshall snow size distribution by melted diameter.
double gunn_marshall_n0_m3_mm(double rate_mm_h);     // 3800 R^-0.87
double gunn_marshall_lambda_per_mm(double rate_mm_h);  // 2.55 R^-0.48
// Holroyd density law capped at ice density, g/cm^3, for a flake of maximum dimension D (mm).
double holroyd_density_g_cm3(double flake_diameter_mm);
// Flake maximum dimension (mm) whose mass equals a water drop of the melted diameter (mm):
// rho_w D_m^3 = rho_s(D_s) D_s^3 with rho_s from holroyd_density_g_cm3.
double snow_flake_diameter_mm(double melted_diameter_mm);
// Locatelli-Hobbs fall speed of an aggregate of maximum dimension D (mm).
double locatelli_hobbs_velocity_m_s(double flake_diameter_mm);

// Extinction coefficient of rain in the visible, per meter: 0.312 R^0.67 km^-1.
double rain_extinction_per_m(double rate_mm_h);
// Koschmieder: beta = 3.912 / V and back.
double koschmieder_beta_per_m(double visibility_m);
double koschmieder_visibility_m(double beta_per_m);

// Response time of a falling particle to changes of the air velocity (s): tau = v_t / g, the time
// constant of linear drag that balances gravity at the terminal velocity.
double response_time_s(double terminal_velocity_m_s);

// N(D) = n0 exp(-lambda D) truncated to [d_min_mm, d_max_mm].
struct ExponentialSizeDistribution {
  double n0_m3_mm = 0;
  double lambda_per_mm = 0;
  double d_min_mm = 0;
  double d_max_mm = 0;

  double density(double d_mm) const;                          // N(D), m^-3 mm^-1 (0 outside)
  double number_density_m3(double lo_mm, double hi_mm) const;  // Int_lo^hi N(D) dD, m^-3
  double number_density_m3() const { return number_density_m3(d_min_mm, d_max_mm); }
  // CDF of the truncated distribution at d (0 below d_min, 1 above d_max).
  double cdf(double d_mm) const;
  // Inverse CDF of the distribution restricted to [lo_mm, hi_mm]; u in [0, 1). Stable for tiny
  // lambda * (hi - lo) (expm1 / log1p).
  double sample_mm(double u, double lo_mm, double hi_mm) const;
  std::string to_string() const;
};

ExponentialSizeDistribution marshall_palmer(double rate_mm_h, double d_min_mm, double d_max_mm);
ExponentialSizeDistribution gunn_marshall(double rate_mm_h, double d_min_mm, double d_max_mm);

// Int N(D) D^3 v(D) dD * 6e-4 pi over [d_min, d_max] (composite Simpson, `steps` even): the
// precipitation rate in mm/h that a population with this size distribution and fall speed carries.
double precipitation_rate_mm_h(const ExponentialSizeDistribution& dist,
                               const std::function<double(double)>& velocity_m_s, int steps = 4000);

}  // namespace weathergs::generator::physics
