#include "generator/lens/optics.h"

#include <algorithm>
#include <cmath>

namespace weathergs::generator::lens {

Eigen::Vector3d reflect(const Eigen::Vector3d& d, const Eigen::Vector3d& n) {
  return d - 2.0 * d.dot(n) * n;
}

std::optional<Eigen::Vector3d> refract(const Eigen::Vector3d& d, const Eigen::Vector3d& n, double eta_i,
                                       double eta_t) {
  const double eta = eta_i / eta_t;
  const double cos_i = std::clamp(-d.dot(n), 0.0, 1.0);
  const double sin2_t = eta * eta * std::max(0.0, 1.0 - cos_i * cos_i);
  if (sin2_t >= 1.0) return std::nullopt;
  const double cos_t = std::sqrt(1.0 - sin2_t);
  Eigen::Vector3d t = eta * d + (eta * cos_i - cos_t) * n;
  return t.normalized();
}

double fresnel_dielectric(double cos_i, double eta_i, double eta_t) {
  cos_i = std::clamp(std::abs(cos_i), 0.0, 1.0);
  const double sin2_t = (eta_i / eta_t) * (eta_i / eta_t) * std::max(0.0, 1.0 - cos_i * cos_i);
  if (sin2_t >= 1.0) return 1.0;
  const double cos_t = std::sqrt(1.0 - sin2_t);
  const double rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
  const double rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
  return std::clamp(0.5 * (rs * rs + rp * rp), 0.0, 1.0);
}

}  // namespace weathergs::generator::lens
