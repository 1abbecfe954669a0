// Rendering airborne particles into one view (docs/generator.md, "Rendering").
//
// A particle's path over the shutter interval [t, t + T] becomes a "splat": a polyline of
// primitives (zero-length ones are dots). Each primitive is a disk of radius R pixels and peak alpha
// a0 moving at constant image speed along a segment; its alpha at a pixel is the fraction of the
// exposure during which the disk covers the pixel, which is Garg & Nayar's tau / T. Two coverage
// kernels, chosen per primitive:
//  * point (R < 0.5 px): mass m = a0 pi R^2 spread over the pixels the segment crosses in proportion
//    to the exact length of the segment inside each pixel (analytic segment-pixel overlap);
//  * disk (R >= 0.5 px): the exact time fraction during which each point is inside the moving disk
//    (segment-circle chord), averaged over S x S points per pixel (S = ceil(24 / R) clamped to 1..8).
// Both conserve the mass a0 pi R^2. Alphas of one particle are summed per pixel, then particles are
// composited order-independently: A = 1 - prod(1 - alpha_i), radiance sum(alpha_i L_i) / sum(alpha_i)
// (exact when particles do not overlap in time and space, which a pixel's time-averaged coverage
// cannot tell apart anyway). A particle behind the clean depth at a pixel contributes nothing there.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/thin_lens.h"
#include "core/image.h"
#include "generator/photometry.h"

namespace weathergs::generator {

enum class StreakMode { kAnalytic, kTimeSamples };
const char* to_string(StreakMode mode);  // "analytic", "time_samples" (the spec's spelling)

// Quality knobs of the particle renderer (the spec's "render" block).
struct RenderOptions {
  StreakMode streak = StreakMode::kAnalytic;
  int segments = 1;            // analytic: straight pieces per exposure (perspective, curvature)
  int time_samples = 16;       // kTimeSamples: dots at the midpoints of N equal time slices
  // A particle is drawn only if the peak alpha it can reach in any pixel is at least this; also
  // sets how far each size class is populated (see visibility_distance_m).
  double visibility_cutoff = 0.01;
  double max_distance_m = 50;  // hard cap on the populated distance (m)
  double near_m = 0.05;        // paths are clipped to camera z >= near_m (closer is a lens droplet)
  bool defocus = true;         // thin-lens blur where the camera has f_number/focal/focus
  void validate(const std::string& where) const;
};


// Depth at which a particle of visual radius r_m and peak alpha a0 stops being visible without
// motion blur or defocus (both only lower its peak alpha): its mass a0 pi (f r / z)^2 in one pixel
// falls below the cutoff at z = f r sqrt(pi a0 / cutoff). Capped at options.max_distance_m.
double visibility_distance_m(double f_px, double r_m, double a0, const RenderOptions& options);

// Light of the particles (docs/record/generator_history.md, "Photometry").
enum class ParticleShading {
  kOptics,    // physical: the particle's optics over the light around it (generator/photometry.h)
  kWeighted,  // paper style: weights of a wide blur of the view and of the sky radiance
};
const char* to_string(ParticleShading shading);

// Albedo of fresh snow in the visible, ~0.9 (Warren 1982, Rev. Geophys. 20(1), Fig. 11: 0.9-0.99 for
// pure fine-grained snow; 0.9 allows for the impurities of falling snow).
constexpr double kSnowAlbedo = 0.9;

struct ParticleAppearance {
  ParticleShading shading = ParticleShading::kOptics;
  double albedo = kSnowAlbedo;  // kOptics, snow: Lambertian flakes
  // kWeighted only: a drop images a ~165 degree cone (Garg & Nayar), much of it outside the frame
  // and, outdoors, much of it sky: the image's neighborhood and the sky weigh about equally.
  double environment_weight = 0.54;  // x wide-cone average of the clean radiance around the particle
  double sky_weight = 0.4;           // x the sky radiance estimate (ambient from outside the image)
};

// Per-view light field shared by the particle stages.
struct EnvironmentLight {
  Image wide;                          // box-blurred clean linear RGB (radius max(W, H) / 4)
  Eigen::Vector3f sky = Eigen::Vector3f::Ones();  // dataset-wide sky radiance estimate (linear)
};
EnvironmentLight make_environment_light(const Image& clean_linear, const Eigen::Vector3f& sky);

// Fog between the camera and a point (set by the fog stage; beta 0 = clear air).
struct FogState {
  double beta_per_m = 0;
  Eigen::Vector3f airlight = Eigen::Vector3f::Zero();
  float transmittance(double ray_length_m) const;
};

// The view being rendered.
struct RenderView {
  Camera camera;             // with the spec's overrides applied
  const Image* depth = nullptr;  // planar z, 1 channel, camera size
  std::optional<ThinLens> lens;  // present when defocus is on and the camera has one
  double f_px() const { return std::sqrt(camera.fx * camera.fy); }
};

// Times at which a path is sampled: analytic: segments + 1 points from t to t + T; time samples:
// the N slice midpoints.
std::vector<double> path_sample_times(const RenderOptions& options, double t_open_s, double exposure_s);

struct SplatPrimitive {
  float x0 = 0, y0 = 0, z0 = 0, x1 = 0, y1 = 0, z1 = 0;  // pixel coords, planar depth
  float radius_px = 0, a0 = 0, weight = 0;               // weight: share of the exposure
};

struct Splat {
  int first = 0, count = 0;          // primitives
  int source = 0;                    // caller's index of the particle
  int y_min = 0, y_max = -1;         // rows touched (inclusive)
  float mid_x = 0, mid_y = 0, mid_z = 0, mid_ray_m = 0;  // where the radiance is looked up
  Eigen::Vector3f radiance = Eigen::Vector3f::Zero();
};

struct SplatList {
  std::vector<Splat> splats;
  std::vector<SplatPrimitive> primitives;
  void append(const SplatList& other);
};

// Builds the splat of one particle from its world positions at path_sample_times(); returns false
// (adding nothing) when it is outside the image, entirely closer than near_m, or below the
// visibility cutoff.
bool add_splat(const RenderView& view, const RenderOptions& options, const Eigen::Vector3d* p_world,
               int num_samples, double visual_radius_m, double opacity, int source, SplatList* out);

struct ParticleRaster {
  Image alpha;                  // 1 channel: 1 - prod(1 - alpha_i) after the depth test
  Image radiance;               // 3 channels: sum(alpha_i L_i) / sum(alpha_i) (0 where alpha is 0)
  std::vector<uint8_t> visible;  // per splat: reached the visibility cutoff in an unoccluded pixel
};

// Sets each splat's radiance at its middle: optics->at(mid) (kOptics; optics must be given) or
// environment_weight * wide(mid) + sky_weight * sky (kWeighted), seen through the fog up to the
// particle: L t + airlight (1 - t), t = exp(-beta * ray length).
void shade_splats(const EnvironmentLight& env, const ParticleRadianceGrid* optics, const FogState& fog,
                  const ParticleAppearance& appearance, SplatList* splats);

// Rasterizes the splats (radiance already set) with the depth test; parallel over row bands,
// deterministic for any thread count.
ParticleRaster rasterize_splats(const RenderView& view, const SplatList& splats,
                                const RenderOptions& options);

// radiance = (1 - A) radiance + A L_particles, in place (linear RGB).
void composite_particles(const ParticleRaster& raster, Image* radiance);

}  // namespace weathergs::generator
