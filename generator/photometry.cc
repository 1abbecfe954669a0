#include "generator/photometry.h"

#include <algorithm>
#include <cmath>

#include "core/constants.h"
#include "core/error.h"
#include "core/parallel.h"

namespace weathergs::generator {

namespace {
// The environment image a kernel samples: about 64 pixels across. A drop's rings span tens of degrees,
// so finer detail averages out; coarser would blur the horizon the kernels straddle.
constexpr int kEnvironmentWidth = 64;
// Impact parameters per water sphere and directions of the Lambert quadrature: a uniform environment
// gives each kernel's energy to 1e-5 (tested); the water grid of a 600x400 view costs 49 ms on 2
// cores (bench_generator_weather, water_radiance_grid_600x400).
constexpr int kWaterSamples = 48;
constexpr int kLambertDirections = 1024;
// Azimuths on a ring of angle theta: ~kRingAzimuths sin(theta), at least kMinAzimuths.
constexpr int kRingAzimuths = 48;
constexpr int kMinAzimuths = 6;
constexpr int kGridStepPx = 16;

// Rings of the Lambert sphere: a Fibonacci sphere of directions grouped by their angle to the ray
// is the same as rings at the Fibonacci latitudes; equal area each.
std::vector<ScatterRing> lambert_rings(int n) {
  std::vector<ScatterRing> rings(static_cast<size_t>(n));
  double sum = 0;
  for (int k = 0; k < n; ++k) {
    const double cos_t = 1.0 - 2.0 * (k + 0.5) / n;  // uniform in cos: equal solid angle 4 pi / n
    const double theta = std::acos(cos_t);
    // theta is the angle between w and d; the phase angle is between w and -d.
    const double w = lambert_sphere_phase(kPi - theta) * 4.0 * kPi / n;
    rings[size_t(k)] = {theta, w};
    sum += w;
  }
  // Exact normalization (the analytic integral is 1): a uniform environment gives albedo exactly.
  for (ScatterRing& r : rings) r.weight /= sum;
  return rings;
}
}  // namespace

double fresnel_reflectance(double cos_i, double n) {
  WGS_CHECK(n > 0);
  cos_i = std::clamp(cos_i, 0.0, 1.0);
  const double sin_t = std::sqrt(std::max(0.0, 1.0 - cos_i * cos_i)) / n;
  if (sin_t >= 1) return 1.0;
  const double cos_t = std::sqrt(1.0 - sin_t * sin_t);
  const double rs = (cos_i - n * cos_t) / (cos_i + n * cos_t);
  const double rp = (n * cos_i - cos_t) / (n * cos_i + cos_t);
  return 0.5 * (rs * rs + rp * rp);
}

std::vector<ScatterRing> water_sphere_rings(int samples) {
  WGS_CHECK_GE(samples, 1);
  const double n = kWaterRefractiveIndex;
  std::vector<ScatterRing> rings;
  for (int k = 0; k < samples; ++k) {
    const double b = std::sqrt((k + 0.5) / samples);  // impact parameter, uniform in disk area
    const double i = std::asin(b), r = std::asin(b / n);
    // Reflectance at entry equals the internal reflectance at r (Stokes relations).
    const double R = fresnel_reflectance(std::cos(i), n), T = (1 - R) * (1 - R);
    // Angle between the light's direction and the camera ray d (0 = from straight behind the drop).
    rings.push_back({kPi - 2 * i, R / samples});                  // external reflection
    rings.push_back({2 * (i - r), T / samples});                  // refracted twice
    const double d2 = kPi + 2 * i - 4 * r;                        // one internal reflection
    rings.push_back({d2 > kPi ? 2 * kPi - d2 : d2, T * R / samples});
  }
  std::sort(rings.begin(), rings.end(), [](const ScatterRing& a, const ScatterRing& b) { return a.theta < b.theta; });
  return rings;
}

double water_sphere_density_per_sr(double theta) {
  constexpr int kBins = 180;
  constexpr double kBin = kPi / kBins;
  static const std::vector<double> table = [] {
    std::vector<double> t(kBins, 0.0);
    for (const ScatterRing& r : water_sphere_rings(100000)) t[size_t(std::clamp(int(r.theta / kBin), 0, kBins - 1))] += r.weight;
    for (int i = 0; i < kBins; ++i) t[size_t(i)] /= 2 * kPi * (std::cos(i * kBin) - std::cos((i + 1) * kBin));
    return t;
  }();
  return table[size_t(std::clamp(int(theta / kBin), 0, kBins - 1))];
}

double lambert_sphere_phase(double alpha) {
  alpha = std::clamp(alpha, 0.0, kPi);
  return 2.0 / (3.0 * kPi * kPi) * (std::sin(alpha) + (kPi - alpha) * std::cos(alpha));
}

ViewEnvironment::ViewEnvironment(const Camera& camera, const Image& clean, const Eigen::Vector3f& sky)
    : camera_(camera), sky_(sky) {
  WGS_CHECK(clean.width == camera.width && clean.height == camera.height && clean.channels >= 3);
  const int factor = std::max(1, clean.width / kEnvironmentWidth);
  const int w = (clean.width + factor - 1) / factor, h = (clean.height + factor - 1) / factor;
  scale_ = 1.0 / factor;
  small_ = Image(w, h, 3, ColorSpace::kLinear);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double s[3] = {0, 0, 0};
      int count = 0;
      for (int yy = y * factor; yy < std::min(clean.height, (y + 1) * factor); ++yy)
        for (int xx = x * factor; xx < std::min(clean.width, (x + 1) * factor); ++xx, ++count)
          for (int c = 0; c < 3; ++c) s[c] += clean.at(xx, yy, c);
      for (int c = 0; c < 3; ++c) small_.at(x, y, c) = float(s[c] / count);
    }
  // Ground: the mean of the pixels that look below the horizon (all pixels if none does).
  double g[3] = {0, 0, 0}, all[3] = {0, 0, 0};
  int64_t n_ground = 0;
  for (int y = 0; y < clean.height; ++y)
    for (int x = 0; x < clean.width; ++x) {
      const bool below = camera.ray_direction_world({x + 0.5, y + 0.5}).z() < 0;
      for (int c = 0; c < 3; ++c) {
        all[c] += clean.at(x, y, c);
        if (below) g[c] += clean.at(x, y, c);
      }
      n_ground += below;
    }
  const double n_all = double(clean.num_pixels());
  for (int c = 0; c < 3; ++c) ground_[c] = float(n_ground > 0 ? g[c] / double(n_ground) : all[c] / n_all);
}

Eigen::Vector3f ViewEnvironment::radiance(const Eigen::Vector3d& w) const {
  const Eigen::Vector3d wc = camera_.rotation() * w;
  if (wc.z() > 1e-9) {
    const double u = camera_.fx * wc.x() / wc.z() + camera_.cx, v = camera_.fy * wc.y() / wc.z() + camera_.cy;
    if (u >= 0 && u < camera_.width && v >= 0 && v < camera_.height) {
      // Bilinear in the small image (pixel centers at +0.5), clamped at its border.
      const double sx = std::clamp(u * scale_ - 0.5, 0.0, small_.width - 1.0);
      const double sy = std::clamp(v * scale_ - 0.5, 0.0, small_.height - 1.0);
      const int x0 = std::min(int(sx), small_.width - 1), y0 = std::min(int(sy), small_.height - 1);
      const int x1 = std::min(x0 + 1, small_.width - 1), y1 = std::min(y0 + 1, small_.height - 1);
      const double fx = sx - x0, fy = sy - y0;
      Eigen::Vector3f out;
      for (int c = 0; c < 3; ++c)
        out[c] = float((1 - fy) * ((1 - fx) * small_.at(x0, y0, c) + fx * small_.at(x1, y0, c)) +
                       fy * ((1 - fx) * small_.at(x0, y1, c) + fx * small_.at(x1, y1, c)));
      return out;
    }
  }
  return w.z() > 0 ? sky_ : ground_;
}

ParticleRadianceGrid::ParticleRadianceGrid(const ViewEnvironment& env, const Camera& camera, ParticleOptics optics,
                                           double albedo, const SunLight* sun) {
  const std::vector<ScatterRing> rings =
      optics == ParticleOptics::kWaterSphere ? water_sphere_rings(kWaterSamples) : lambert_rings(kLambertDirections);
  const double scale = optics == ParticleOptics::kWaterSphere ? 1.0 : albedo;
  nx_ = (camera.width + kGridStepPx - 1) / kGridStepPx + 1;
  ny_ = (camera.height + kGridStepPx - 1) / kGridStepPx + 1;
  nodes_.assign(size_t(nx_) * ny_, Eigen::Vector3f::Zero());
  parallel_for(0, int64_t(nx_) * ny_, [&](int64_t node) {
    const int gx = int(node % nx_), gy = int(node / nx_);
    const Eigen::Vector3d d =
        camera.ray_direction_world({std::min(gx * kGridStepPx, camera.width), std::min(gy * kGridStepPx, camera.height)});
    // Orthonormal basis around d.
    const Eigen::Vector3d helper = std::abs(d.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
    const Eigen::Vector3d e1 = d.cross(helper).normalized(), e2 = d.cross(e1);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (const ScatterRing& ring : rings) {
      const double st = std::sin(ring.theta), ct = std::cos(ring.theta);
      const int n_phi = std::max(kMinAzimuths, int(std::ceil(kRingAzimuths * st)));
      Eigen::Vector3d ring_sum = Eigen::Vector3d::Zero();
      for (int j = 0; j < n_phi; ++j) {
        const double phi = 2 * kPi * (j + 0.5) / n_phi;
        const Eigen::Vector3d w = ct * d + st * (std::cos(phi) * e1 + std::sin(phi) * e2);
        ring_sum += env.radiance(w).cast<double>();
      }
      sum += ring.weight * ring_sum / n_phi;
    }
    if (sun) {
      const double theta = std::acos(std::clamp(sun->to_sun_world.dot(d), -1.0, 1.0));
      const double k = optics == ParticleOptics::kWaterSphere ? water_sphere_density_per_sr(theta)
                                                               : lambert_sphere_phase(kPi - theta);
      sum += k * sun->irradiance.cast<double>();
    }
    nodes_[size_t(node)] = (scale * sum).cast<float>();
  });
}

Eigen::Vector3f ParticleRadianceGrid::at(double x, double y) const {
  const double gx = std::clamp(x / kGridStepPx, 0.0, nx_ - 1.0), gy = std::clamp(y / kGridStepPx, 0.0, ny_ - 1.0);
  const int x0 = std::min(int(gx), nx_ - 2), y0 = std::min(int(gy), ny_ - 2);  // nx_, ny_ >= 2
  const int x1 = std::min(x0 + 1, nx_ - 1), y1 = std::min(y0 + 1, ny_ - 1);
  const float fx = float(gx - x0), fy = float(gy - y0);
  auto n = [&](int i, int j) { return nodes_[size_t(j) * nx_ + i]; };
  return (1 - fy) * ((1 - fx) * n(x0, y0) + fx * n(x1, y0)) + fy * ((1 - fx) * n(x0, y1) + fx * n(x1, y1));
}

}  // namespace weathergs::generator
