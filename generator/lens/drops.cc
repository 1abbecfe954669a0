#include "generator/lens/drops.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/constants.h"
#include "core/error.h"
#include "core/rng.h"

namespace weathergs::generator::lens {

namespace {


double clamp_contact(double theta) {
  return std::clamp(theta, kMinContactAngleRad, kPi - kMinContactAngleRad);
}

// The lens glass in camera coordinates: at glass_distance_m on the optical axis, rotated by the tilt
// about camera x and then y.
GlassFrame lens_frame(const LensDropletSpec& spec) {
  const double tx = spec.glass_tilt_deg[0] * kPi / 180, ty = spec.glass_tilt_deg[1] * kPi / 180;
  Eigen::Matrix3d r = (Eigen::AngleAxisd(ty, Eigen::Vector3d::UnitY()) *
                       Eigen::AngleAxisd(tx, Eigen::Vector3d::UnitX()))
                          .toRotationMatrix();
  GlassFrame f;
  f.origin = Eigen::Vector3d(0, 0, spec.glass_distance_m);
  f.x_axis = r.col(0);
  f.y_axis = r.col(1);
  f.normal = r.col(2);
  return f;
}

GlassFrame window_frame(const WindowPose& w) {
  GlassFrame f;
  f.origin = w.center_world;
  f.normal = w.normal_world.normalized();
  Eigen::Vector3d down = -w.up_world + w.up_world.dot(f.normal) * f.normal;
  f.y_axis = down.normalized();
  f.x_axis = f.y_axis.cross(f.normal);
  return f;
}

// Bounding box, in frame coordinates, of where the camera's corner rays meet the plane (camera
// coordinates). Falls back to a square of the glass distance when a corner ray misses the plane.
void view_footprint(const GlassFrame& f, const Camera& cam, Eigen::Vector2d* lo, Eigen::Vector2d* hi) {
  *lo = Eigen::Vector2d::Constant(1e300);
  *hi = Eigen::Vector2d::Constant(-1e300);
  const double dist = f.origin.dot(f.normal);
  for (double u : {0.0, double(cam.width)}) {
    for (double v : {0.0, double(cam.height)}) {
      Eigen::Vector3d d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      double dn = d.dot(f.normal);
      Eigen::Vector2d q;
      if (dn > 1e-9 && dist / dn < 1e3 * std::abs(dist)) {
        Eigen::Vector3d p = d * (dist / dn) - f.origin;
        q = {p.dot(f.x_axis), p.dot(f.y_axis)};
      } else {
        q = Eigen::Vector2d::Constant(std::abs(dist)) * (u > 0 ? 1 : -1);
      }
      *lo = lo->cwiseMin(q);
      *hi = hi->cwiseMax(q);
    }
  }
}

}  // namespace

std::string GlassFrame::to_string() const {
  std::ostringstream s;
  s << "GlassFrame{origin " << origin.transpose() << ", x " << x_axis.transpose() << ", y "
    << y_axis.transpose() << ", normal " << normal.transpose() << "}";
  return s.str();
}

double Drop::base_radius_m() const {
  const double th = clamp_contact(contact_angle_rad);
  return th <= kPi / 2 ? outline_radius_m : outline_radius_m * std::sin(th);
}

double Drop::sphere_radius_m() const {
  const double th = clamp_contact(contact_angle_rad);
  return th <= kPi / 2 ? outline_radius_m / std::sin(th) : outline_radius_m;
}

std::string Drop::to_string() const {
  std::ostringstream s;
  s << "Drop{id " << id << ", center_m " << center_m.transpose() << ", outline_radius_m "
    << outline_radius_m << ", contact_angle_deg " << contact_angle_rad * 180 / kPi << ", slide_m_s "
    << slide_speed_m_s << "}";
  return s.str();
}

LensDropletSpec resolve_lens_droplet_spec(const LensDropletSpec& spec, const Camera& reference) {
  LensDropletSpec out = spec;
  if (spec.attach != Attach::kWindow || spec.window) return out;
  WindowPose w;
  const Eigen::Matrix3d world_from_camera_r = reference.rotation().transpose();
  const Eigen::Vector3d forward = world_from_camera_r.col(2);
  w.center_world = reference.center_world() + spec.glass_distance_m * forward;
  w.normal_world = forward;
  // Gravity along world -z; a camera looking straight up or down takes its image "down" instead.
  w.up_world = Eigen::Vector3d::UnitZ();
  if (std::abs(forward.z()) > 0.999) w.up_world = -world_from_camera_r.col(1);
  GlassFrame f;
  f.origin = Eigen::Vector3d(0, 0, spec.glass_distance_m);
  Eigen::Vector2d lo, hi;
  view_footprint(f, reference, &lo, &hi);
  const double grow = 1 + 2 * spec.sampling_margin;
  w.size_m = {(hi.x() - lo.x()) * grow, (hi.y() - lo.y()) * grow};
  out.window = w;
  return out;
}

DropField sample_drop_field(const LensDropletSpec& spec, uint64_t seed, const Camera& reference) {
  WGS_CHECK(spec.attach == Attach::kLens || spec.window.has_value());
  DropField field;
  field.attach = spec.attach;
  field.drop_side = spec.drop_side;
  const double max_outline_m = spec.radius_mm[1] * 1e-3;
  if (spec.attach == Attach::kLens) {
    field.frame = lens_frame(spec);
    Eigen::Vector2d lo, hi;
    view_footprint(field.frame, reference, &lo, &hi);
    const Eigen::Vector2d grow = (hi - lo) * spec.sampling_margin + Eigen::Vector2d::Constant(max_outline_m);
    field.region_min = lo - grow;
    field.region_max = hi + grow;
  } else {
    field.frame = window_frame(*spec.window);
    field.region_min = {-spec.window->size_m[0] / 2, -spec.window->size_m[1] / 2};
    field.region_max = -field.region_min;
  }
  const double r_lo = spec.radius_mm[0] * 1e-3, r_hi = spec.radius_mm[1] * 1e-3;
  const double th_lo = spec.contact_angle_deg[0] * kPi / 180, th_hi = spec.contact_angle_deg[1] * kPi / 180;
  field.drops.reserve(spec.count);
  for (int i = 0; i < spec.count; ++i) {
    Rng rng(seed, kStreamLensDrops, uint64_t(i));
    Drop d;
    d.id = i;
    const double u = rng.uniform_double(), v = rng.uniform_double();
    d.center_m = field.region_min + Eigen::Vector2d(u, v).cwiseProduct(field.region_max - field.region_min);
    const double ur = rng.uniform_double();
    d.outline_radius_m = spec.radius_distribution == RadiusDistribution::kLogUniform
                             ? std::exp(std::log(r_lo) + ur * (std::log(r_hi) - std::log(r_lo)))
                             : r_lo + ur * (r_hi - r_lo);
    d.contact_angle_rad = th_lo + rng.uniform_double() * (th_hi - th_lo);
    d.slide_speed_m_s =
        d.outline_radius_m >= spec.slide_min_radius_mm * 1e-3 ? spec.slide_speed_mm_s * 1e-3 : 0.0;
    field.drops.push_back(d);
  }
  return field;
}

PlacedDrop make_placed_drop(int id, const Eigen::Vector3d& base_center, const Eigen::Vector3d& water_normal,
                            double outline_radius, double contact_angle_rad) {
  Drop d;
  d.outline_radius_m = outline_radius;
  d.contact_angle_rad = contact_angle_rad;
  PlacedDrop p;
  p.id = id;
  p.base_center = base_center;
  p.contact_angle_rad = clamp_contact(contact_angle_rad);
  p.outline_radius = outline_radius;
  p.base_radius = d.base_radius_m();
  p.sphere_radius = d.sphere_radius_m();
  p.sphere_center = base_center - water_normal * (p.sphere_radius * std::cos(p.contact_angle_rad));
  return p;
}

GlassPlane place_glass(const DropField& field, const Camera& camera) {
  GlassPlane plane;
  Eigen::Vector3d origin = field.frame.origin, normal = field.frame.normal;
  if (field.attach == Attach::kWindow) {
    origin = camera.to_camera(origin);
    normal = camera.rotation() * normal;
  }
  plane.point = origin;
  plane.water_normal = field.drop_side == DropSide::kScene ? normal : Eigen::Vector3d(-normal);
  return plane;
}

std::vector<PlacedDrop> place_drops(const DropField& field, const Camera& camera, double time_s) {
  const GlassPlane plane = place_glass(field, camera);
  std::vector<PlacedDrop> out;
  out.reserve(field.drops.size());
  for (const Drop& d : field.drops) {
    Eigen::Vector2d c = d.center_m + Eigen::Vector2d(0, d.slide_speed_m_s * time_s);
    // A drop that slid off the sampled glass is gone (it ran off the lens or the pane).
    if (c.y() - d.outline_radius_m > field.region_max.y()) continue;
    Eigen::Vector3d base = field.frame.point(c.x(), c.y());
    base = field.attach == Attach::kWindow ? camera.to_camera(base) : base;
    out.push_back(make_placed_drop(d.id, base, plane.water_normal, d.outline_radius_m, d.contact_angle_rad));
  }
  return out;
}

}  // namespace weathergs::generator::lens
