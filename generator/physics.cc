#include "generator/physics.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.h"
#include "generator/physics_constants.h"

namespace weathergs::generator::physics {

double marshall_palmer_lambda_per_mm(double rate_mm_h) {
  WGS_CHECK_GT(rate_mm_h, 0.0);
  return kMarshallPalmerLambdaCoef_per_mm * std::pow(rate_mm_h, kMarshallPalmerLambdaExp);
}

double atlas_velocity_m_s(double d_mm) {
  return std::max(0.0, kAtlasA_m_s - kAtlasB_m_s * std::exp(-kAtlasC_per_mm * d_mm));
}

double beard_chuang_axis_ratio(double d_mm) {
  // The polynomial is 1.0048 at D = 0: clamping at 1 keeps small drops spherical.
  const double d = std::clamp(d_mm, 0.0, 9.0) / 10.0;  // cm
  double r = 0, p = 1;
  for (double c : kBeardChuang_cm) r += c * p, p *= d;
  return std::min(r, 1.0);
}

double gunn_marshall_n0_m3_mm(double rate_mm_h) {
  WGS_CHECK_GT(rate_mm_h, 0.0);
  return kGunnMarshallN0Coef_m3_mm * std::pow(rate_mm_h, kGunnMarshallN0Exp);
}

double gunn_marshall_lambda_per_mm(double rate_mm_h) {
  WGS_CHECK_GT(rate_mm_h, 0.0);
  return kGunnMarshallLambdaCoef_per_mm * std::pow(rate_mm_h, kGunnMarshallLambdaExp);
}

double holroyd_density_g_cm3(double flake_d_mm) {
  WGS_CHECK_GT(flake_d_mm, 0.0);
  return std::min(kIceDensity_g_cm3, kHolroydCoef_g_cm2 / (flake_d_mm / 10.0));
}

double snow_flake_diameter_mm(double melted_d_mm) {
  WGS_CHECK_GT(melted_d_mm, 0.0);
  const double dm_cm = melted_d_mm / 10.0;
  // Holroyd branch: rho_w Dm^3 = (c / Ds) Ds^3  =>  Ds = sqrt(rho_w Dm^3 / c).
  const double ds_holroyd_cm = std::sqrt(kWaterDensity_g_cm3 * dm_cm * dm_cm * dm_cm / kHolroydCoef_g_cm2);
  // Ice branch (density capped): Ds = Dm (rho_w / rho_ice)^(1/3). The larger one is consistent.
  const double ds_ice_cm = dm_cm * std::cbrt(kWaterDensity_g_cm3 / kIceDensity_g_cm3);
  return 10.0 * std::max(ds_holroyd_cm, ds_ice_cm);
}

double locatelli_hobbs_velocity_m_s(double flake_d_mm) {
  if (!(flake_d_mm > 0)) return 0.0;
  return kLocatelliHobbsCoef_m_s * std::pow(flake_d_mm, kLocatelliHobbsExp);
}

double rain_extinction_per_m(double rate_mm_h) {
  if (!(rate_mm_h > 0)) return 0.0;
  return kRainExtinctionCoef_per_km * std::pow(rate_mm_h, kRainExtinctionExp) / 1000.0;
}

double koschmieder_beta_per_m(double visibility_m) {
  WGS_CHECK_GT(visibility_m, 0.0);
  return kKoschmiederConstant / visibility_m;
}

double koschmieder_visibility_m(double beta_per_m) {
  WGS_CHECK_GT(beta_per_m, 0.0);
  return kKoschmiederConstant / beta_per_m;
}

double response_time_s(double v) { return std::max(0.0, v) / kGravity_m_s2; }

double ExponentialSizeDistribution::density(double d) const {
  if (d < d_min_mm || d > d_max_mm) return 0.0;
  return n0_m3_mm * std::exp(-lambda_per_mm * d);
}

double ExponentialSizeDistribution::number_density_m3(double lo, double hi) const {
  lo = std::max(lo, d_min_mm);
  hi = std::min(hi, d_max_mm);
  if (!(hi > lo)) return 0.0;
  // N0 e^{-L lo} (1 - e^{-L (hi - lo)}) / L, written with expm1 so that L -> 0 gives N0 (hi - lo).
  const double w = hi - lo;
  const double x = lambda_per_mm * w;
  const double frac = x > 1e-12 ? -std::expm1(-x) / lambda_per_mm : w;
  return n0_m3_mm * std::exp(-lambda_per_mm * lo) * frac;
}

double ExponentialSizeDistribution::cdf(double d) const {
  if (d <= d_min_mm) return 0.0;
  if (d >= d_max_mm) return 1.0;
  return number_density_m3(d_min_mm, d) / number_density_m3(d_min_mm, d_max_mm);
}

double ExponentialSizeDistribution::sample_mm(double u, double lo, double hi) const {
  const double w = hi - lo;
  const double x = lambda_per_mm * w;
  if (x < 1e-12) return lo + u * w;
  const double d = lo - std::log1p(u * std::expm1(-x)) / lambda_per_mm;
  return std::clamp(d, lo, hi);
}

std::string ExponentialSizeDistribution::to_string() const {
  std::ostringstream s;
  s << "N(D) = " << n0_m3_mm << " exp(-" << lambda_per_mm << " D) on [" << d_min_mm << ", "
    << d_max_mm << "] mm";
  return s.str();
}

ExponentialSizeDistribution marshall_palmer(double rate, double d_min, double d_max) {
  return {kMarshallPalmerN0_m3_mm, marshall_palmer_lambda_per_mm(rate), d_min, d_max};
}

ExponentialSizeDistribution gunn_marshall(double rate, double d_min, double d_max) {
  return {gunn_marshall_n0_m3_mm(rate), gunn_marshall_lambda_per_mm(rate), d_min, d_max};
}

double precipitation_rate_mm_h(const ExponentialSizeDistribution& dist,
                               const std::function<double(double)>& v, int steps) {
  WGS_CHECK(steps > 0 && steps % 2 == 0);
  const double a = dist.d_min_mm, b = dist.d_max_mm, h = (b - a) / steps;
  auto f = [&](double d) { return dist.density(d) * d * d * d * v(d); };
  double s = f(a) + f(b);
  for (int i = 1; i < steps; ++i) s += f(a + i * h) * (i % 2 ? 4.0 : 2.0);
  return kRainRateFactor * s * h / 3.0;
}

}  // namespace weathergs::generator::physics
