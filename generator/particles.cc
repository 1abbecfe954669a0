#include "generator/particles.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/constants.h"
#include "core/error.h"
#include "core/rng.h"

namespace weathergs::generator {

namespace {
// Streams of the generator's Rng keys (core/rng.h): one per (species, class) and one per wind.
constexpr uint64_t kStreamParticles = 0x5041525400000000ull;  // "PART"
constexpr uint64_t kStreamWind = 0x57494e4400000000ull;       // "WIND"

uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// 64-bit key of a cell; collisions (probability ~2^-64 per pair) would only repeat a cell's content.
uint64_t cell_key(const CellIndex& c) {
  return splitmix64(splitmix64(splitmix64(uint64_t(c.x())) ^ uint64_t(c.y())) ^ uint64_t(c.z()));
}

}  // namespace

const char* to_string(Species s) { return s == Species::kRain ? "rain" : "snow"; }

std::string ParticleId::to_string() const {
  std::ostringstream o;
  o << generator::to_string(Species(species)) << "/" << size_class << "/" << cell.x() << ":" << cell.y()
    << ":" << cell.z() << "/" << index;
  return o.str();
}

int poisson_from_uniform(double lambda, double u, double u2) {
  if (!(lambda > 0)) return 0;
  if (lambda > 200) {  // normal approximation; relative error of the tails is irrelevant here
    const double z = std::sqrt(-2.0 * std::log(std::max(u, 1e-300))) * std::cos(2 * kPi * u2);
    return std::max(0, int(std::lround(lambda + std::sqrt(lambda) * z)));
  }
  double p = std::exp(-lambda), cdf = p;
  int k = 0;
  while (u > cdf && k < 2000) {
    ++k;
    p *= lambda / k;
    cdf += p;
    if (p < 1e-300 && double(k) > lambda) break;
  }
  return k;
}

void SpeciesOptions::validate(const std::string& where) const {
  auto bad = [&](const std::string& what) { throw InputError(where, what); };
  if (!(std::isfinite(rate_mm_h) && rate_mm_h >= 0 && rate_mm_h <= 2000))
    bad("rate_mm_h must be in [0, 2000], got " + std::to_string(rate_mm_h));
  if (!(d_min_mm > 0 && d_max_mm > d_min_mm && d_max_mm <= 20))
    bad("diameter_range_mm must satisfy 0 < min < max <= 20");
  if (size_classes < 1 || size_classes > 64) bad("size_classes must be in [1, 64]");
  if (!(opacity > 0 && opacity <= 1)) bad("opacity must be in (0, 1]");
  if (!(particles_per_cell >= 1 && particles_per_cell <= 1000)) bad("particles_per_cell must be in [1, 1000]");
  if (!(size_scale >= 1 && size_scale <= 100)) bad("size_scale must be in [1, 100], got " + std::to_string(size_scale));
  if (!(density_scale > 0 && density_scale <= 100))
    bad("density_scale must be in (0, 100], got " + std::to_string(density_scale));
  for (int i = 0; i < 2; ++i) {
    if (!(flutter_amplitude_m[i] >= 0 && flutter_amplitude_m[i] <= 10)) bad("flutter amplitude_m must be in [0, 10]");
    if (!(flutter_frequency_hz[i] >= 0 && flutter_frequency_hz[i] <= 100)) bad("flutter frequency_hz must be in [0, 100]");
  }
  if (flutter_amplitude_m[0] > flutter_amplitude_m[1] || flutter_frequency_hz[0] > flutter_frequency_hz[1])
    bad("flutter ranges must be [min, max] with min <= max");
  wind.validate(where);
  if (wind.mean_m_s.norm() > 200) bad("wind_m_s must be below 200 m/s");
}

physics::ExponentialSizeDistribution SpeciesOptions::distribution() const {
  WGS_CHECK_GT(rate_mm_h, 0.0);
  return species == Species::kRain ? physics::marshall_palmer(rate_mm_h, d_min_mm, d_max_mm)
                                   : physics::gunn_marshall(rate_mm_h, d_min_mm, d_max_mm);
}

double SpeciesOptions::visual_radius_m(double d_mm) const {
  if (species == Species::kSnow) return size_scale * 0.5e-3 * physics::snow_flake_diameter_mm(d_mm);
  // An oblate spheroid of axis ratio r = b/a and equal volume seen from the side has area
  // pi r_eq^2 r^(1/3); the equal-area disk has radius r_eq r^(1/6).
  const double r = oblate ? physics::beard_chuang_axis_ratio(d_mm) : 1.0;
  return size_scale * 0.5e-3 * d_mm * std::pow(r, 1.0 / 6.0);
}

double SpeciesOptions::fall_speed_m_s(double d_mm) const {
  return species == Species::kRain ? physics::atlas_velocity_m_s(d_mm)
                                   : physics::locatelli_hobbs_velocity_m_s(physics::snow_flake_diameter_mm(d_mm));
}

ParticleField::ParticleField(const SpeciesOptions& options, uint64_t seed)
    : options_(options), seed_(seed),
      wind_(options.wind, seed, kStreamWind + uint64_t(options.species)) {
  if (!(options.rate_mm_h > 0)) return;  // rate 0: an empty field
  const physics::ExponentialSizeDistribution dist = options.distribution();
  const int n = options.size_classes;
  for (int k = 0; k < n; ++k) {
    SizeClass c;
    c.lo_mm = options.d_min_mm * std::pow(options.d_max_mm / options.d_min_mm, double(k) / n);
    c.hi_mm = options.d_min_mm * std::pow(options.d_max_mm / options.d_min_mm, double(k + 1) / n);
    c.number_density_m3 = options.density_scale * dist.number_density_m3(c.lo_mm, c.hi_mm);
    c.frame_fall_m_s = options.fall_speed_m_s(0.5 * (c.lo_mm + c.hi_mm));
    // Cells of at most 2 m follow the thin apex and edges of a frustum closely for sparse classes.
    c.cell_m = std::clamp(std::cbrt(options.particles_per_cell / std::max(c.number_density_m3, 1e-12)), 0.05, 2.0);
    c.max_visual_radius_m = options.visual_radius_m(c.hi_mm);
    classes_.push_back(c);
  }
}

Eigen::Vector3d ParticleField::frame_velocity(int k) const {
  return options_.wind.mean_m_s - Eigen::Vector3d(0, 0, classes_[size_t(k)].frame_fall_m_s);
}

void ParticleField::cell_particles(int k, const CellIndex& cell, std::vector<Particle>* out) const {
  const SizeClass& c = classes_[size_t(k)];
  Rng rng(seed_, kStreamParticles + uint64_t(options_.species) * 256 + uint64_t(k), cell_key(cell));
  const double lambda = c.number_density_m3 * c.cell_m * c.cell_m * c.cell_m;
  const double u1 = rng.uniform_double(), u2 = rng.uniform_double();
  const int count = poisson_from_uniform(lambda, u1, u2);
  const physics::ExponentialSizeDistribution dist = options_.distribution();
  const bool snow = options_.species == Species::kSnow;
  for (int j = 0; j < count; ++j) {
    double u[9];
    for (double& x : u) x = rng.uniform_double();  // a fixed number of draws per particle
    Particle p;
    p.id = {int(options_.species), k, cell, j};
    p.q0 = Eigen::Vector3d(u[0], u[1], u[2]) * c.cell_m;
    p.diameter_mm = dist.sample_mm(u[3], c.lo_mm, c.hi_mm);
    p.visual_radius_m = options_.visual_radius_m(p.diameter_mm);
    p.fall_m_s = options_.fall_speed_m_s(p.diameter_mm);
    p.tau_s = physics::response_time_s(p.fall_m_s);
    if (snow) {
      const auto lerp = [](const double r[2], double t) { return r[0] + (r[1] - r[0]) * t; };
      p.flutter_amp_m = lerp(options_.flutter_amplitude_m, u[4]);
      p.flutter_omega = 2 * kPi * lerp(options_.flutter_frequency_hz, u[5]);
      p.flutter_phase = 2 * kPi * u[6];
      p.flutter_b = u[7];
      p.flutter_angle = 2 * kPi * u[8];
    }
    out->push_back(p);
  }
}

ParticleState ParticleField::state(const Particle& p, double t, double t_ref) const {
  ParticleState s;
  states(p, &t, 1, t_ref, &s);
  return s;
}

void ParticleField::states(const Particle& p, const double* t, int n, double t_ref, ParticleState* out) const {
  const SizeClass& c = classes_[size_t(p.id.size_class)];
  const Eigen::Vector3d origin = p.id.cell.cast<double>() * c.cell_m;
  const Eigen::Vector3d u_frame = frame_velocity(p.id.size_class);
  const double dfall = c.frame_fall_m_s - p.fall_m_s;
  // Motion relative to the frame at t_ref and the n times: own fall speed, gusts, flutter.
  constexpr int kBatch = 16;
  double times[kBatch + 1];
  Eigen::Vector3d disp[kBatch + 1], vel[kBatch + 1];
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  for (int first = 0; first < n; first += kBatch) {
    const int m = std::min(kBatch, n - first);
    times[0] = t_ref;
    for (int i = 0; i < m; ++i) times[i + 1] = t[first + i];
    wind_.particle_response(origin + p.q0, p.fall_m_s, p.tau_s, times, m + 1, disp, vel);
    for (int i = 0; i <= m; ++i) {
      disp[i].z() += dfall * times[i];
      vel[i].z() += dfall;
      if (p.flutter_amp_m > 0) {
        const double ca = std::cos(p.flutter_angle), sa = std::sin(p.flutter_angle);
        const double ph = p.flutter_omega * times[i] + p.flutter_phase;
        const double x = p.flutter_amp_m * std::cos(ph), y = p.flutter_amp_m * p.flutter_b * std::sin(ph);
        const double vx = -p.flutter_amp_m * p.flutter_omega * std::sin(ph);
        const double vy = p.flutter_amp_m * p.flutter_b * p.flutter_omega * std::cos(ph);
        disp[i] += Eigen::Vector3d(ca * x - sa * y, sa * x + ca * y, 0);
        vel[i] += Eigen::Vector3d(ca * vx - sa * vy, sa * vx + ca * vy, 0);
      }
    }
    // The wrap into the cell is chosen at t_ref: the path is continuous over the given times.
    const Eigen::Vector3d q_ref = p.q0 + disp[0];
    for (int a = 0; a < 3; ++a) shift[a] = std::floor(q_ref[a] / c.cell_m) * c.cell_m;
    for (int i = 0; i < m; ++i) {
      out[first + i].p_world = origin + u_frame * times[i + 1] + p.q0 + disp[i + 1] - shift;
      out[first + i].v_world = u_frame + vel[i + 1];
    }
  }
}

}  // namespace weathergs::generator
