// Wind: a mean wind plus seeded, divergence-free turbulence, and the response of a falling particle
// to it.
//
// Model (docs/generator.md): u(x, t) = W + sum_m a_m sin(k_m . (x - W t) - omega_m t + phi_m), a
// random-Fourier-mode field (Kraichnan 1970) with a_m perpendicular to k_m, so div u = 0 exactly.
// Wavelengths are log-spaced over [length_scale / 8, 2 length_scale]; |a_m| ~ |k_m|^(-1/3) gives
// the Kolmogorov -5/3 energy spectrum over log-spaced bands; omega_m = rms |k_m| is the eddy turnover
// rate. The field is frozen into the mean flow (Taylor), so a particle carried by W sees only the
// modes' change along its fall and their turnover. A particle responds to the gusts as a first-order
// low-pass with response time tau = v_t / g (physics::response_time_s): snow (tau ~ 0.1 s) follows
// them, rain (tau ~ 0.9 s) lags and damps them. Along the undisturbed path the phase of each mode is
// linear in time, so displacement and velocity are closed-form: a particle's position is a pure
// function of time.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace weathergs::generator {

struct WindOptions {
  Eigen::Vector3d mean_m_s = Eigen::Vector3d::Zero();  // world frame (+z up)
  double turbulence_rms_m_s = 0;  // rms of each component of the gusts; 0 = steady wind
  double length_scale_m = 10;     // integral length scale of the gusts, > 0
  int modes = 32;                 // Fourier modes, 1..1024

  void validate(const std::string& where) const;  // InputError naming the field
};

class WindField {
 public:
  WindField(const WindOptions& options, uint64_t seed, uint64_t stream);

  const Eigen::Vector3d& mean() const { return options_.mean_m_s; }
  double rms() const { return options_.turbulence_rms_m_s; }
  // Air velocity (m/s) at p_world and time t_s.
  Eigen::Vector3d air_velocity(const Eigen::Vector3d& p_world, double t_s) const;

  // Gust response of a particle whose undisturbed path is x_ref + W t - fall ẑ t (x_ref: where it
  // would be at t = 0), with response time tau_s: displacement relative to that path and velocity
  // relative to W - fall ẑ, at time t_s. Steady-state response (no start-up transient).
  void particle_response(const Eigen::Vector3d& x_ref, double fall_m_s, double tau_s, double t_s,
                         Eigen::Vector3d* displacement_m, Eigen::Vector3d* velocity_m_s) const;
  // The same at n times at once (the per-mode phase at t = 0 is computed once).
  void particle_response(const Eigen::Vector3d& x_ref, double fall_m_s, double tau_s, const double* t_s, int n,
                         Eigen::Vector3d* displacement_m, Eigen::Vector3d* velocity_m_s) const;
  // Upper bound of |velocity_m_s| of particle_response (sum of mode amplitudes).
  double max_gust_m_s() const { return max_gust_; }

 private:
  struct Mode {
    Eigen::Vector3d k, a;
    double phase = 0, omega = 0;
  };
  WindOptions options_;
  std::vector<Mode> modes_;
  double max_gust_ = 0;
};

}  // namespace weathergs::generator
