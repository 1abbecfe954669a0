// One world-space particle state for all views (docs/generator.md, "Particle state").
//
// A species (rain or snow) is split into size classes. Class k drifts as a whole with the frame
// velocity U_k = W - v_k ẑ (mean wind, fall speed of the class's middle diameter) and tiles that
// drifting frame with cubic cells of side s_k. Cell c of class k holds Poisson(n_k s_k^3) particles
// whose attributes come from Rng(seed, stream(species, k), hash(c)): the population is a
// homogeneous Poisson process of the right size distribution, defined everywhere, and only the cells
// a camera can see are ever generated. A particle never leaves its cell: its motion relative to the
// frame (own fall speed minus v_k, gust response, flutter) is wrapped periodically into the cell, so
// a particle that leaves through one face re-enters through the opposite one and the density stays
// exactly uniform. Its position is therefore a pure function of (seed, id, time).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "generator/physics.h"
#include "generator/wind.h"

namespace weathergs::generator {

enum class Species { kRain = 0, kSnow = 1 };
const char* to_string(Species s);

struct SpeciesOptions {
  Species species = Species::kRain;
  double rate_mm_h = 0;       // rain rate, or snow water-equivalent rate; 0 = no particles
  double d_min_mm = 0.1;      // size range (snow: melted diameter); smaller drops are invisible
  double d_max_mm = 6.0;      // rain 6 mm (larger drops break up), snow 5 mm melted
  int size_classes = 24;      // log-spaced classes over [d_min, d_max]
  bool oblate = true;         // rain: Beard-Chuang cross-section (equal-area disk of the oblate drop)
  WindOptions wind;
  // Snow flutter: a horizontal elliptical sway x = A (cos(w t + phi) e1 + b sin(w t + phi) e2),
  // A, f = w / 2 pi, phi, b and e1 drawn per flake, uniform in these ranges.
  double flutter_amplitude_m[2] = {0.01, 0.05};
  double flutter_frequency_hz[2] = {0.5, 2.0};
  double opacity = 1.0;              // peak alpha of a particle's image (snow is translucent)
  double particles_per_cell = 32;    // expected particles per cell (sets the cell size)
  // The paper style's exaggerations (docs/generator.md, "Styles"); 1 = physical.
  double size_scale = 1.0;         // multiplies every particle's visual radius
  double density_scale = 1.0;        // multiplies the number density of every size class

  void validate(const std::string& where) const;
  physics::ExponentialSizeDistribution distribution() const;
  // Visual (equal-area) radius in m of a particle of physical diameter d_mm (snow: melted).
  double visual_radius_m(double d_mm) const;
  double fall_speed_m_s(double d_mm) const;
};

struct SizeClass {
  double lo_mm = 0, hi_mm = 0;
  double number_density_m3 = 0;
  double frame_fall_m_s = 0;       // v_k
  double cell_m = 0;               // s_k
  double max_visual_radius_m = 0;  // of the class's largest particle
};

using CellIndex = Eigen::Matrix<int64_t, 3, 1>;

struct ParticleId {
  int species = 0, size_class = 0;
  CellIndex cell = CellIndex::Zero();
  int index = 0;
  std::string to_string() const;  // "rain/3/12:-4:7/5" (species/class/cell/index)
};

struct Particle {
  ParticleId id;
  double diameter_mm = 0;       // rain: equal-volume diameter; snow: melted diameter
  double visual_radius_m = 0;
  double fall_m_s = 0;          // terminal velocity
  double tau_s = 0;             // gust response time
  Eigen::Vector3d q0 = Eigen::Vector3d::Zero();  // position in its cell at t = 0
  double flutter_amp_m = 0, flutter_omega = 0, flutter_phase = 0, flutter_b = 0, flutter_angle = 0;
};

struct ParticleState {
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_world = Eigen::Vector3d::Zero();
};

class ParticleField {
 public:
  ParticleField(const SpeciesOptions& options, uint64_t seed);

  const SpeciesOptions& options() const { return options_; }
  const std::vector<SizeClass>& classes() const { return classes_; }
  const WindField& wind() const { return wind_; }
  Eigen::Vector3d frame_velocity(int k) const;  // U_k

  // Appends the particles of cell `cell` of class k (deterministic, any order of calls).
  void cell_particles(int k, const CellIndex& cell, std::vector<Particle>* out) const;
  // Position and velocity at time t_s, wrapped into the particle's cell at time t_ref_s: for a fixed
  // t_ref the path is continuous in t (used over one exposure); state(p, t, t) is canonical.
  ParticleState state(const Particle& p, double t_s, double t_ref_s) const;
  // state() at n times with one t_ref (cheaper: the gust phases are shared).
  void states(const Particle& p, const double* t_s, int n, double t_ref_s, ParticleState* out) const;

 private:
  SpeciesOptions options_;
  uint64_t seed_;
  std::vector<SizeClass> classes_;
  WindField wind_;
};

// Expected number of particles of a Poisson process with mean lambda drawn with uniform u
// (inversion; normal approximation above lambda = 200).
int poisson_from_uniform(double lambda, double u, double u2);

}  // namespace weathergs::generator
