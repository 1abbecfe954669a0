// Interface optics of a dielectric boundary: Snell refraction, mirror reflection and the exact
// unpolarized Fresnel reflectance (Hecht, Optics, 5th ed., eqs. 4.42-4.45; average of s and p).
#pragma once

#include <Eigen/Core>
#include <optional>

namespace weathergs::generator::lens {

// Water at 20 C for visible light (Hale & Querry 1973: 1.333 at 589 nm).
constexpr double kWaterRefractiveIndex = 1.333;
// Crown glass (Schott N-BK7: 1.5168 at 587.6 nm), the cover glass of camera modules; the Cycles
// lens reference's default plate (docs/record/cycles_validation.md, "The cover glass and the camera's body").
constexpr double kCrownGlassRefractiveIndex = 1.52;

// Mirror reflection of direction d about unit normal n (either orientation).
Eigen::Vector3d reflect(const Eigen::Vector3d& d, const Eigen::Vector3d& n);

// Refracts unit direction d at a boundary with unit normal n facing the incoming side
// (d.dot(n) <= 0), from index eta_i into eta_t. nullopt on total internal reflection.
std::optional<Eigen::Vector3d> refract(const Eigen::Vector3d& d, const Eigen::Vector3d& n, double eta_i,
                                       double eta_t);

// Unpolarized Fresnel reflectance for cos_i = |cos| of the angle of incidence, in [0, 1]; 1 under
// total internal reflection.
double fresnel_dielectric(double cos_i, double eta_i, double eta_t);

}  // namespace weathergs::generator::lens
