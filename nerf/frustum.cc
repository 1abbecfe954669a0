#include "nerf/frustum.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/constants.h"
#include "core/error.h"
#include "core/json_fields.h"

namespace weathergs::nerf {

namespace {

// Mean rotation of the cameras: z = mean viewing direction, x = mean camera x made orthogonal.
Eigen::Matrix3d mean_orientation(const std::vector<Camera>& cameras) {
  Eigen::Vector3d z = Eigen::Vector3d::Zero(), x = Eigen::Vector3d::Zero();
  for (const Camera& c : cameras) {
    const Eigen::Matrix3d r = c.rotation();  // rows = camera axes in world
    x += r.row(0).transpose();
    z += r.row(2).transpose();
  }
  WGS_CHECK(z.norm() > 0);
  z.normalize();
  x -= x.dot(z) * z;
  if (x.norm() < 1e-6) x = z.unitOrthogonal();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d m;
  m.row(0) = x.transpose();
  m.row(1) = y.transpose();
  m.row(2) = z.transpose();
  return m;
}

// The most a camera may turn away from the mean viewing direction.
constexpr double kMaxTurnDeg = 75;

}  // namespace

namespace {

// An image-plane interval [lo, hi] as the JSON pair [lo, hi].
template <typename Fields>
void interval(Fields& f, const char* key, double& lo, double& hi) {
  f.custom(
      key, [&] { return Json{lo, hi}; },
      [&](const JsonReader& r, const std::string& k) {
        const std::array<double, 2> v = r.get_array<2>(k);
        lo = v[0], hi = v[1];
      });
}

constexpr auto kFrameFields = [](auto& s, auto& f) {  // every key required
  f.custom(
      "ref_from_world",
      [&] {
        Json rows = Json::array();
        for (int i = 0; i < 3; ++i) rows.push_back({s.ref_from_world(i, 0), s.ref_from_world(i, 1), s.ref_from_world(i, 2)});
        return rows;
      },
      [&](const JsonReader& r, const std::string& k) {
        const JsonReader m = r.child(k);
        if (!m.is_array() || m.size() != 3) throw InputError(r.where(k), "expected a 3x3 array");
        for (size_t i = 0; i < 3; ++i) {
          const JsonReader row = m.at(i);
          if (!row.is_array() || row.size() != 3) throw InputError(row.where(), "expected 3 numbers");
          for (size_t j = 0; j < 3; ++j) s.ref_from_world(int(i), int(j)) = row.at(j).template as<double>();
        }
      });
  f("center", s.center);
  interval(f, "u", s.u0, s.u1);
  interval(f, "v", s.v0, s.v1);
  f("w_max", s.w_max, json_fields::Bounds{1e-9, 1e9});
};

}  // namespace

Json FrustumFrame::to_json() const { return json_fields::write(*this, kFrameFields); }

FrustumFrame FrustumFrame::from_json(const JsonReader& r) {
  FrustumFrame f = json_fields::read(r, FrustumFrame{}, kFrameFields, json_fields::Absent::kError);
  if (!(f.u1 > f.u0 && f.v1 > f.v0)) throw InputError(r.where("u"), "expected increasing u and v bounds");
  return f;
}


FrustumFrame forward_facing_frame(const std::vector<Camera>& cameras, double near_m) {
  WGS_CHECK(!cameras.empty());
  if (!(near_m > 0 && std::isfinite(near_m))) throw InputError("nerf frame", "near plane must be > 0 m");
  FrustumFrame f;
  f.ref_from_world = mean_orientation(cameras);
  f.center = Eigen::Vector3d::Zero();
  for (const Camera& c : cameras) f.center += c.center_world();
  f.center /= double(cameras.size());
  f.w_max = 1.0 / near_m;
  const double cos_max = std::cos(kMaxTurnDeg * kPi / 180);
  double u0 = std::numeric_limits<double>::infinity(), u1 = -u0, v0 = u0, v1 = -u0;
  for (const Camera& c : cameras) {
    const Eigen::Vector3d axis = f.ref_from_world * c.rotation().row(2).transpose();
    if (axis.z() < cos_max)
      throw InputError("camera '" + c.name + "'",
                       "looks " + std::to_string(int(std::acos(std::clamp(axis.z(), -1.0, 1.0)) * 180 / kPi)) +
                           " degrees away from the mean viewing direction: the radiance-field backend needs a "
                           "forward-facing capture (every camera within 75 degrees)");
    // The image corners' rays from near to the horizon, in the reference frame.
    const Eigen::Vector3d o = f.to_ref(c.center_world());
    for (double px : {0.0, double(c.width)})
      for (double py : {0.0, double(c.height)}) {
        const Eigen::Vector3d d = f.ref_from_world * c.ray_direction_world(Eigen::Vector2d(px, py));
        if (d.z() <= 1e-3)
          throw InputError("camera '" + c.name + "'",
                           "an image corner looks sideways or backwards relative to the mean viewing direction: "
                           "the radiance-field backend needs a forward-facing capture");
        for (double w = f.w_max; w >= 0; w -= f.w_max / 64) {
          double u, v;
          if (w <= 0) {
            u = d.x() / d.z(), v = d.y() / d.z();
          } else {
            const double t = (1.0 / w - o.z()) / d.z();
            if (t <= 0) continue;  // this camera sits in front of that depth
            const Eigen::Vector3d p = o + t * d;
            u = p.x() * w, v = p.y() * w;
          }
          u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
        }
      }
  }
  const double mu = 0.04 * (u1 - u0), mv = 0.04 * (v1 - v0);
  f.u0 = u0 - mu, f.u1 = u1 + mu, f.v0 = v0 - mv, f.v1 = v1 + mv;
  return f;
}

double near_from_points(const std::vector<Camera>& cameras, const std::vector<Eigen::Vector3d>& points,
                        double min_near_m, double fallback_m) {
  WGS_CHECK(!cameras.empty());
  const Eigen::Matrix3d r = mean_orientation(cameras);
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const Camera& cam : cameras) c += cam.center_world();
  c /= double(cameras.size());
  std::vector<double> z;
  for (const Eigen::Vector3d& p : points) {
    const double d = (r * (p - c)).z();
    if (d > 0 && std::isfinite(d)) z.push_back(d);
  }
  if (z.size() < kNearMinPoints) return fallback_m;
  const size_t k = z.size() / 100;
  std::nth_element(z.begin(), z.begin() + k, z.end());
  return std::max(min_near_m, 0.5 * z[k]);
}

std::vector<Eigen::Vector3d> near_plane_points(const std::vector<ColmapPoint3D>& points) {
  std::vector<Eigen::Vector3d> checked, all;
  for (const ColmapPoint3D& p : points) {
    all.push_back(p.xyz);
    if (p.track.size() >= kNearMinTrack) checked.push_back(p.xyz);
  }
  return checked.size() >= kNearMinPoints ? checked : all;
}

}  // namespace weathergs::nerf
