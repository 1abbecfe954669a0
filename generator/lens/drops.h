// Drops on the glass: seeded sampling (lens- or window-attached), sliding under gravity, and their
// spherical-cap geometry in a view's camera frame.
//
// A drop is a spherical cap on the glass plane. Its "outline radius" (the spec's radius_mm) is the
// radius of what the drop covers seen along the glass normal: the contact (base) radius a for
// contact angles <= 90 degrees, the sphere radius R above (the bulge overhangs the base). Then
// R = a / sin(theta), cap height h = R (1 - cos(theta)), sphere center R cos(theta) below the glass
// on the water side's opposite (theta < 90) or above it (theta > 90).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/json_reader.h"
#include "generator/lens/lens_spec.h"

namespace weathergs::generator::lens {

// Contact angles are clamped to [kMinContactAngleRad, pi - kMinContactAngleRad]: below 0.057
// degrees a 3 mm drop is flatter than 1.5 um, optically a film, and its sphere radius (a / sin)
// would exceed what float ray tracing resolves.
constexpr double kMinContactAngleRad = 1e-3;

// Rng streams of this module (core/rng.h): drops are keyed on their id, pixels on (view, pixel).
constexpr uint64_t kStreamLensDrops = 0x4c454e5344524f50ull;   // "LENSDROP"
constexpr uint64_t kStreamLensPixels = 0x4c454e53504958ull;    // "LENSPIX"

// A plane with 2D coordinates: point(u, v) = origin + u x_axis + v y_axis. y_axis is the glass's
// "down" (gravity); normal = x_axis x y_axis points away from the cameras.
struct GlassFrame {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d x_axis = Eigen::Vector3d::UnitX();
  Eigen::Vector3d y_axis = Eigen::Vector3d::UnitY();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d point(double u, double v) const { return origin + u * x_axis + v * y_axis; }
  std::string to_string() const;
};

struct Drop {
  int id = 0;
  Eigen::Vector2d center_m = Eigen::Vector2d::Zero();  // base center at time 0, glass coordinates
  double outline_radius_m = 0;
  double contact_angle_rad = 0;
  double slide_speed_m_s = 0;  // along the glass's y axis (down)

  double base_radius_m() const;
  double sphere_radius_m() const;
  std::string to_string() const;
};

// All drops of a dataset. The frame is in camera coordinates for attach "lens" (the same for every
// view) and in world coordinates for attach "window".
struct DropField {
  Attach attach = Attach::kLens;
  DropSide drop_side = DropSide::kScene;
  GlassFrame frame;
  Eigen::Vector2d region_min = Eigen::Vector2d::Zero(), region_max = Eigen::Vector2d::Zero();
  std::vector<Drop> drops;
};

// Fills what the spec leaves to the dataset: the window pose of attach "window" when absent (the
// pane at glass_distance_m in front of `reference`, facing it, sized to its view plus the margin).
LensDropletSpec resolve_lens_droplet_spec(const LensDropletSpec& spec, const Camera& reference);

// Samples spec.count drops, keyed on (seed, kStreamLensDrops, drop id): uniform positions over the
// sampled region, radii from spec.radius_distribution, contact angles uniform in the spec's range.
// The lens-attach region is the reference camera's view of the glass, widened by sampling_margin
// per side and by the largest outline radius. `spec` must be resolved.
DropField sample_drop_field(const LensDropletSpec& spec, uint64_t seed, const Camera& reference);

// A drop in one view's camera frame at one time, ready for tracing.
struct PlacedDrop {
  int id = 0;
  Eigen::Vector3d base_center = Eigen::Vector3d::Zero();
  Eigen::Vector3d sphere_center = Eigen::Vector3d::Zero();
  double base_radius = 0, sphere_radius = 0, outline_radius = 0, contact_angle_rad = 0;
};

// The glass plane in camera coordinates, `water_normal` pointing to the side the water sits on.
struct GlassPlane {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d water_normal = Eigen::Vector3d::UnitZ();
  double height(const Eigen::Vector3d& p) const { return (p - point).dot(water_normal); }
};

// The glass plane and the drops (still on the sampled region after sliding) in `camera`'s frame at
// time_s. Drops are positioned analytically from time 0, so the result does not depend on which
// views were placed before.
GlassPlane place_glass(const DropField& field, const Camera& camera);
std::vector<PlacedDrop> place_drops(const DropField& field, const Camera& camera, double time_s);

PlacedDrop make_placed_drop(int id, const Eigen::Vector3d& base_center, const Eigen::Vector3d& water_normal,
                            double outline_radius, double contact_angle_rad);

}  // namespace weathergs::generator::lens
