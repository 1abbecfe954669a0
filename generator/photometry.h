// Radiance of a falling particle from the light around it (docs/record/generator_history.md, "Photometry").
//
// A drop or flake is tiny against the distances to what lights it, so the radiance it sends along the
// camera ray d depends on d only: L(d) = integral over directions w of E(w) k(angle(w, d)) dw, with E
// the light arriving at the camera's position and k the particle's scattering kernel:
// - water sphere (rain; Garg & Nayar 2004, sec. 3): the external reflection, the twice-refracted ray
//   and the ray with one internal reflection, each with its unpolarized Fresnel weight, over the
//   drop's disk. The refracted ray alone turns by 2 (i - r), up to 82.8 degrees at grazing incidence:
//   a drop shows a ~165 degree cone of its surroundings, most of it outside the camera's frame;
// - Lambertian sphere (snow): the disk-averaged radiance per unit irradiance from phase angle a is
//   albedo (2 / (3 pi^2)) (sin a + (pi - a) cos a) (the Lambert sphere's phase law).
// E is the clean view where w falls inside the image; outside it, the sky radiance above the horizon
// (world +z up) and below it the mean of the view's below-horizon pixels ("ground"). A sun, when
// given, adds a point source.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/camera.h"
#include "core/image.h"

namespace weathergs::generator {

// Relative refractive index of water to air at visible wavelengths (IAPWS, 589 nm, 20 C: 1.333).
constexpr double kWaterRefractiveIndex = 1.333;

// Unpolarized Fresnel reflectance of a smooth dielectric interface of relative index n (> 0) at
// incidence cos_i in [0, 1] from the side of index 1; total internal reflection gives 1.
double fresnel_reflectance(double cos_i, double n);

// One ring of a rotationally symmetric kernel: light from directions at angle theta (radians) from the
// camera ray contributes weight x (mean environment radiance on that ring).
struct ScatterRing {
  double theta = 0;
  double weight = 0;
};

// Rings of a water sphere: `samples` impact parameters uniform in disk area, three paths each
// (reflection, refraction, one internal reflection). The weights sum to the energy those paths carry
// (about 0.99 of the light; the rest leaves after two or more internal reflections).
std::vector<ScatterRing> water_sphere_rings(int samples);

// The water sphere's kernel per steradian at angle theta (for a point source such as the sun): the
// weights of 10^5 impact parameters binned by theta in 1 degree bins over each bin's solid angle.
double water_sphere_density_per_sr(double theta);

// Disk-averaged radiance of a white Lambertian sphere per unit irradiance arriving at phase angle
// alpha (radians) between the light's direction and the direction towards the camera.
double lambert_sphere_phase(double alpha);

// The light around one view.
class ViewEnvironment {
 public:
  // clean_linear: the clean view (linear RGB, camera size); sky: the dataset's sky radiance estimate.
  ViewEnvironment(const Camera& camera, const Image& clean_linear, const Eigen::Vector3f& sky);
  // Radiance arriving at the camera from world direction w (unit).
  Eigen::Vector3f radiance(const Eigen::Vector3d& w_world) const;
  const Eigen::Vector3f& ground() const { return ground_; }

 private:
  Camera camera_;
  Image small_;        // the clean view box-downsampled by scale_ (sampled bilinearly)
  double scale_ = 1;   // small_ pixels per camera pixel
  Eigen::Vector3f sky_, ground_;
};

// A distant sun: direction towards it (world, unit) and its irradiance on a surface facing it, in the
// images' linear units (Blender's sun "strength" x colour: a white Lambertian surface facing it has
// radiance irradiance / pi). Particles are taken as sunlit (no shadow from the scene).
struct SunLight {
  Eigen::Vector3d to_sun_world = Eigen::Vector3d::UnitZ();
  Eigen::Vector3f irradiance = Eigen::Vector3f::Zero();
};

enum class ParticleOptics { kWaterSphere, kLambertSphere };

// L(d) on a coarse grid of the view's pixels, interpolated bilinearly (it changes slowly across the
// image: the kernels are tens of degrees wide). Deterministic, parallel over grid nodes.
class ParticleRadianceGrid {
 public:
  // sun: adds its light through the same kernel (a delta in direction), when given.
  ParticleRadianceGrid(const ViewEnvironment& environment, const Camera& camera, ParticleOptics optics,
                       double albedo, const SunLight* sun = nullptr);
  Eigen::Vector3f at(double x_px, double y_px) const;

 private:
  int step_ = 16, nx_ = 0, ny_ = 0;
  std::vector<Eigen::Vector3f> nodes_;
};

}  // namespace weathergs::generator
