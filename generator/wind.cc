#include "generator/wind.h"

#include <cmath>

#include "core/constants.h"
#include "core/error.h"
#include "core/rng.h"

namespace weathergs::generator {

namespace {

Eigen::Vector3d uniform_unit_vector(Rng& rng) {
  const double z = 2.0 * rng.uniform_double() - 1.0;
  const double phi = 2.0 * kPi * rng.uniform_double();
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return {r * std::cos(phi), r * std::sin(phi), z};
}

}  // namespace

void WindOptions::validate(const std::string& where) const {
  if (!mean_m_s.allFinite()) throw InputError(where, "wind_m_s must be finite");
  if (!(std::isfinite(turbulence_rms_m_s) && turbulence_rms_m_s >= 0))
    throw InputError(where, "turbulence rms_m_s must be >= 0, got " + std::to_string(turbulence_rms_m_s));
  if (!(std::isfinite(length_scale_m) && length_scale_m > 0))
    throw InputError(where, "turbulence length_scale_m must be > 0, got " + std::to_string(length_scale_m));
  if (modes < 1 || modes > 1024)
    throw InputError(where, "turbulence modes must be in [1, 1024], got " + std::to_string(modes));
}

WindField::WindField(const WindOptions& options, uint64_t seed, uint64_t stream) : options_(options) {
  if (options.turbulence_rms_m_s <= 0) return;
  const int m = options.modes;
  const double k_min = 2 * kPi / (2.0 * options.length_scale_m);
  const double k_max = 2 * kPi / (options.length_scale_m / 8.0);
  double sum_a2 = 0;
  for (int i = 0; i < m; ++i) {
    Rng rng(seed, stream, uint64_t(i));
    const double f = m == 1 ? 0.5 : double(i) / (m - 1);
    const double kmag = k_min * std::pow(k_max / k_min, f);
    Mode mode;
    mode.k = kmag * uniform_unit_vector(rng);
    // Amplitude direction: a random unit vector projected onto the plane perpendicular to k.
    Eigen::Vector3d dir;
    do {
      dir = uniform_unit_vector(rng);
      dir -= dir.dot(mode.k) / mode.k.squaredNorm() * mode.k;
    } while (dir.norm() < 1e-3);
    mode.a = dir.normalized() * std::pow(kmag, -1.0 / 3.0);
    mode.phase = 2 * kPi * rng.uniform_double();
    sum_a2 += mode.a.squaredNorm();
    modes_.push_back(mode);
  }
  // <|u|^2> = sum |a|^2 / 2 must equal 3 rms^2 (isotropic).
  const double scale = options.turbulence_rms_m_s * std::sqrt(6.0 / sum_a2);
  for (Mode& mode : modes_) {
    mode.a *= scale;
    mode.omega = options.turbulence_rms_m_s * mode.k.norm();
    max_gust_ += mode.a.norm();
  }
}

Eigen::Vector3d WindField::air_velocity(const Eigen::Vector3d& p, double t) const {
  Eigen::Vector3d u = options_.mean_m_s;
  for (const Mode& m : modes_)
    u += m.a * std::sin(m.k.dot(p - options_.mean_m_s * t) - m.omega * t + m.phase);
  return u;
}

void WindField::particle_response(const Eigen::Vector3d& x_ref, double fall, double tau, double t,
                                  Eigen::Vector3d* disp, Eigen::Vector3d* vel) const {
  particle_response(x_ref, fall, tau, &t, 1, disp, vel);
}

void WindField::particle_response(const Eigen::Vector3d& x_ref, double fall, double tau, const double* t, int n,
                                  Eigen::Vector3d* disp, Eigen::Vector3d* vel) const {
  for (int i = 0; i < n; ++i) disp[i].setZero(), vel[i].setZero();
  for (const Mode& m : modes_) {
    // Phase along the undisturbed path: k.(x_ref - fall z t) - omega t + phase = theta0 + Omega t.
    const double theta0 = m.k.dot(x_ref) + m.phase;
    const double omega = -(m.k.z() * fall + m.omega);
    // First-order low-pass of the sinusoid Im(a e^{i(theta0 + Omega t)}): multiply by
    // c = 1 / (1 + i Omega tau) (gain 1/sqrt(1 + (Omega tau)^2), lag atan(Omega tau)).
    const double ot = omega * tau, inv = 1.0 / (1.0 + ot * ot);
    const double cr = inv, ci = -ot * inv;
    const double s0 = std::sin(theta0), c0 = std::cos(theta0);
    // e0 = c e^{i theta0}
    const double er = cr * c0 - ci * s0, ei = cr * s0 + ci * c0;
    for (int i = 0; i < n; ++i) {
      const double h = 0.5 * omega * t[i];
      const double sh = std::sin(h), ch = std::cos(h);
      // e^{i Omega t} = (e^{i h})^2
      const double c2 = ch * ch - sh * sh, s2 = 2 * sh * ch;
      // velocity: Im(e0 e^{i Omega t})
      vel[i] += m.a * (er * s2 + ei * c2);
      // displacement: Im(e0 (e^{i Omega t} - 1) / (i Omega)) = t sinc(h) Im(e0 e^{i h})
      const double sinc_h = std::abs(h) < 1e-8 ? 1.0 - h * h / 6.0 : sh / h;
      disp[i] += m.a * (t[i] * sinc_h * (er * sh + ei * ch));
    }
  }
}

}  // namespace weathergs::generator
