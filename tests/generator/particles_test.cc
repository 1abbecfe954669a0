// The world-space particle state: statistics of the population, wind, and time consistency.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/rng.h"
#include "generator/particles.h"
#include "generator/stages.h"

namespace weathergs::generator {
namespace {

SpeciesOptions rain_options(double rate, Eigen::Vector3d wind = {2, 0, 0}, double rms = 1.0) {
  SpeciesOptions o;
  o.species = Species::kRain;
  o.rate_mm_h = rate;
  o.wind.mean_m_s = wind;
  o.wind.turbulence_rms_m_s = rms;
  return o;
}

SpeciesOptions snow_options(double rate) {
  SpeciesOptions o = rain_options(rate);
  o.species = Species::kSnow;
  o.d_max_mm = 5.0;
  o.opacity = 0.8;
  return o;
}

// Particles of all classes in the cells covering [0, extent]^3 of the frame at t = 0.
std::vector<Particle> particles_in_box(const ParticleField& field, double extent, int max_per_class) {
  std::vector<Particle> all;
  for (int k = 0; k < int(field.classes().size()); ++k) {
    const double s = field.classes()[size_t(k)].cell_m;
    const int n = std::max(1, int(std::floor(extent / s)));
    std::vector<Particle> cls;
    for (int x = 0; x < n && int(cls.size()) < max_per_class; ++x)
      for (int y = 0; y < n; ++y)
        for (int z = 0; z < n; ++z) field.cell_particles(k, CellIndex(x, y, z), &cls);
    all.insert(all.end(), cls.begin(), cls.end());
  }
  return all;
}

TEST(ParticleField, NumberDensityMatchesTheDistribution) {
  const ParticleField field(rain_options(25), 11);
  // Per class: count in many cells vs n_k * volume; Poisson, so within 5 sigma.
  for (int k = 0; k < int(field.classes().size()); k += 5) {
    const SizeClass& c = field.classes()[size_t(k)];
    std::vector<Particle> ps;
    const int cells = 400;
    for (int i = 0; i < cells; ++i) field.cell_particles(k, CellIndex(i, -i, 3), &ps);
    const double expected = c.number_density_m3 * std::pow(c.cell_m, 3) * cells;
    EXPECT_NEAR(double(ps.size()), expected, 5 * std::sqrt(expected) + 1) << "class " << k;
    for (const Particle& p : ps) {
      EXPECT_GE(p.diameter_mm, c.lo_mm);
      EXPECT_LE(p.diameter_mm, c.hi_mm);
    }
  }
}

TEST(ParticleField, SizesFollowTheTruncatedDistribution) {
  // Mix classes in proportion to their number densities by sampling a fixed volume, then KS.
  for (Species sp : {Species::kRain, Species::kSnow}) {
    SpeciesOptions o = sp == Species::kRain ? rain_options(25) : snow_options(2.5);
    o.d_min_mm = 0.5;  // keeps the tiny-drop classes from dominating the sample size
    const ParticleField field(o, 3);
    std::vector<double> d;
    // Equal volume per class: V = 300 m^3 sampled as whole cells.
    for (int k = 0; k < int(field.classes().size()); ++k) {
      const SizeClass& c = field.classes()[size_t(k)];
      const int cells = std::max(1, int(std::lround(300.0 / std::pow(c.cell_m, 3))));
      std::vector<Particle> ps;
      for (int i = 0; i < cells; ++i) field.cell_particles(k, CellIndex(i, 0, 0), &ps);
      for (const Particle& p : ps) d.push_back(p.diameter_mm);
    }
    ASSERT_GT(d.size(), 2000u);
    const physics::ExponentialSizeDistribution dist = o.distribution();
    std::sort(d.begin(), d.end());
    double ks = 0;
    const double n = double(d.size());
    for (size_t i = 0; i < d.size(); ++i) {
      const double f = dist.cdf(d[i]);
      ks = std::max({ks, std::abs(f - i / n), std::abs(f - (i + 1) / n)});
    }
    // Whole cells make the per-class volume differ from 300 m^3 by < 1 cell: < 1% for these
    // sizes; KS at significance 0.001 (1.95 / sqrt(n)) plus that 1%.
    EXPECT_LT(ks, 1.95 / std::sqrt(n) + 0.01) << to_string(sp) << " n=" << n;
  }
}

TEST(ParticleField, GenerationIsKeyedOnTheCell) {
  const ParticleField field(rain_options(25), 5);
  std::vector<Particle> a, b;
  field.cell_particles(7, CellIndex(3, -2, 9), &a);
  field.cell_particles(1, CellIndex(0, 0, 0), &b);  // another call in between changes nothing
  b.clear();
  field.cell_particles(7, CellIndex(3, -2, 9), &b);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].q0, b[i].q0);
    EXPECT_EQ(a[i].diameter_mm, b[i].diameter_mm);
  }
  const ParticleField other(rain_options(25), 6);
  std::vector<Particle> c;
  other.cell_particles(7, CellIndex(3, -2, 9), &c);
  EXPECT_TRUE(c.empty() || a.empty() || c[0].q0 != a[0].q0);
}

TEST(ParticleField, VelocityIsTheDerivativeOfPositionAndWrapsStayInTheCell) {
  for (Species sp : {Species::kRain, Species::kSnow}) {
    const ParticleField field(sp == Species::kRain ? rain_options(25, {5, 1, 0}, 2.0) : snow_options(2.5), 9);
    const std::vector<Particle> ps = particles_in_box(field, 3.0, 50);
    ASSERT_FALSE(ps.empty());
    for (size_t i = 0; i < ps.size(); i += 7) {
      const Particle& p = ps[i];
      for (double t : {0.0, 1.3, 250.0}) {
        // Central difference in double, step 1e-5 s: truncation ~1e-9 m/s, rounding ~1e-6 m/s at
        // positions of ~1e3 m.
        const double h = 1e-5;
        const Eigen::Vector3d fd =
            (field.state(p, t + h, t).p_world - field.state(p, t - h, t).p_world) / (2 * h);
        EXPECT_LT((fd - field.state(p, t, t).v_world).norm(), 1e-3) << p.id.to_string() << " t=" << t;
        // Canonical position lies in the cell's current box.
        const SizeClass& c = field.classes()[size_t(p.id.size_class)];
        const Eigen::Vector3d local =
            field.state(p, t, t).p_world - field.frame_velocity(p.id.size_class) * t - p.id.cell.cast<double>() * c.cell_m;
        for (int a = 0; a < 3; ++a) {
          EXPECT_GE(local[a], -1e-9);
          EXPECT_LT(local[a], c.cell_m + 1e-9);
        }
      }
    }
  }
}

TEST(Wind, TurbulenceIsDivergenceFreeWithTheRequestedRms) {
  WindOptions o;
  o.mean_m_s = {3, 0, 0};
  o.turbulence_rms_m_s = 1.5;
  const WindField w(o, 4, 1);
  double sum2 = 0;
  int n = 0;
  for (int i = 0; i < 4000; ++i) {
    Rng rng(1, 2, uint64_t(i));
    const Eigen::Vector3d p(rng.uniform(-200, 200), rng.uniform(-200, 200), rng.uniform(0, 50));
    const double t = rng.uniform(0, 100);
    const Eigen::Vector3d u = w.air_velocity(p, t) - o.mean_m_s;
    sum2 += u.squaredNorm();
    ++n;
    if (i < 200) {
      const double h = 1e-4;  // central differences: error ~ h^2 |k|^3 |a| ~ 1e-6
      double div = 0;
      for (int a = 0; a < 3; ++a) {
        Eigen::Vector3d e = Eigen::Vector3d::Zero();
        e[a] = h;
        div += (w.air_velocity(p + e, t)[a] - w.air_velocity(p - e, t)[a]) / (2 * h);
      }
      EXPECT_NEAR(div, 0.0, 1e-5);
    }
  }
  // Per-component rms over random space-time points: the 32 random modes give ~10% sampling spread.
  EXPECT_NEAR(std::sqrt(sum2 / n / 3.0), 1.5, 0.3);
}

TEST(Wind, SnowFollowsGustsRainLagsThem) {
  WindOptions o;
  o.mean_m_s = {4, 0, 0};
  o.turbulence_rms_m_s = 2.0;
  const WindField w(o, 8, 1);
  auto gust_rms = [&](double fall) {
    double s = 0;
    for (int i = 0; i < 2000; ++i) {
      Rng rng(3, 4, uint64_t(i));
      const Eigen::Vector3d x(rng.uniform(-100, 100), rng.uniform(-100, 100), rng.uniform(0, 30));
      Eigen::Vector3d d, v;
      w.particle_response(x, fall, physics::response_time_s(fall), rng.uniform(0, 50), &d, &v);
      s += v.squaredNorm();
    }
    return std::sqrt(s / 2000 / 3);
  };
  const double air = gust_rms(0.0);  // tau = 0: the air itself along a non-falling path
  const double snow = gust_rms(1.0), rain = gust_rms(9.0);
  EXPECT_GT(snow / air, 0.8);
  EXPECT_LT(rain / air, 0.6);
}

TEST(ParticleField, ZeroRateIsEmpty) {
  const ParticleField field(rain_options(0.0), 1);
  EXPECT_TRUE(field.classes().empty());
}

TEST(Poisson, InversionMatchesMeanAndVariance) {
  for (double lambda : {0.3, 5.0, 40.0, 500.0}) {
    double s = 0, s2 = 0;
    const int n = 20000;
    for (int i = 0; i < n; ++i) {
      Rng r(2, 9, uint64_t(i));
      const double u = r.uniform_double(), u2 = r.uniform_double();
      const double k = poisson_from_uniform(lambda, u, u2);
      s += k, s2 += k * k;
    }
    const double mean = s / n, var = s2 / n - mean * mean;
    EXPECT_NEAR(mean, lambda, 5 * std::sqrt(lambda / n));
    EXPECT_NEAR(var / lambda, 1.0, 0.1);
  }
}

}  // namespace
}  // namespace weathergs::generator

namespace weathergs::generator {
namespace {

TEST(PopulatedVolume, FollowsWhatTheCameraSeesNotWhereItIs) {
  // The cells enumerated for a view depend on its frustum only: moving the camera 10 km away and
  // 1000 s later changes the count by lattice alignment only (within 15%), and nothing is kept
  // between views.
  SpeciesOptions o;
  o.rate_mm_h = 25;
  o.wind.mean_m_s = {3, 1, 0};
  o.wind.turbulence_rms_m_s = 0.8;
  const ParticleField field(o, 2);
  Camera cam;
  cam.name = "v";
  cam.width = 600, cam.height = 400, cam.fx = cam.fy = 520, cam.cx = 300, cam.cy = 200;
  cam.exposure_s = 1.0 / 60;
  Eigen::Matrix3d r;
  r << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  auto count = [&](const Eigen::Vector3d& center, double t) {
    cam.camera_from_world.setIdentity();
    cam.camera_from_world.topLeftCorner<3, 3>() = r;
    cam.camera_from_world.topRightCorner<3, 1>() = -r * center;
    cam.time_s = t;
    size_t n = 0;
    for (int k = 0; k < int(field.classes().size()); k += 3) n += visible_cells(field, k, cam, 0.05, 6.0).size();
    return double(n);
  };
  const double here = count({0, 0, 1.6}, 0.0), far = count({1e4, -3e3, 50}, 1000.0);
  EXPECT_GT(here, 100);
  EXPECT_NEAR(far / here, 1.0, 0.15);
}

}  // namespace
}  // namespace weathergs::generator
