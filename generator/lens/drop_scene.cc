#include "generator/lens/drop_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "core/constants.h"
#include "core/error.h"

namespace weathergs::generator::lens {

namespace {

std::atomic<int64_t> g_devices_created{0};

constexpr double kInf = std::numeric_limits<double>::infinity();
// A crossing may sit this far below the glass (m) and still count as on the water side: far below
// any cap height we resolve (>= 1e-9 m), far above the double rounding of points near the camera.
constexpr double kAnalyticHeightTolerance = 1e-12;
// Triangulated caps come back with float hit distances (~1e-7 relative error at 3 cm).
constexpr double kTriangleHeightTolerance = 1e-8;
// Relative margin for "strictly inside another drop's ball" (double rounding of squared distances).
constexpr double kInsideRelTolerance = 1e-12;
// Cosine below which a ray counts as parallel to the glass (no plane crossing).
constexpr double kParallelCos = 1e-15;
// Exit directions with camera z below this look backwards or along the image plane: they cannot be
// projected into the view and take the environment radiance.
constexpr double kMinForwardZ = 1e-6;

const char* error_name(RTCError code) {
  switch (code) {
    case RTC_ERROR_UNKNOWN: return "unknown";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
    default: return "none";
  }
}

void plane_basis(const Eigen::Vector3d& n, Eigen::Vector3d* e1, Eigen::Vector3d* e2) {
  Eigen::Vector3d a = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  *e1 = n.cross(a).normalized();
  *e2 = n.cross(*e1);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
EmbreeDevice::EmbreeDevice() {
  device_ = rtcNewDevice(nullptr);
  if (!device_) {
    throw InternalError(std::string("embree: rtcNewDevice failed: ") + error_name(rtcGetDeviceError(nullptr)));
  }
  rtcSetDeviceErrorFunction(device_, &EmbreeDevice::on_error, this);
  ++g_devices_created;
}

EmbreeDevice::~EmbreeDevice() {
  if (device_) rtcReleaseDevice(device_);
}

int64_t EmbreeDevice::num_created() { return g_devices_created.load(); }

void EmbreeDevice::on_error(void* self, RTCError code, const char* message) {
  // Called from inside Embree: record only; the wrapper throws once Embree has returned.
  auto* dev = static_cast<EmbreeDevice*>(self);
  std::lock_guard<std::mutex> lock(dev->mutex_);
  if (dev->error_.empty())
    dev->error_ = std::string(error_name(code)) + (message ? std::string(": ") + message : "");
}

void EmbreeDevice::throw_if_error(const std::string& during) const {
  std::string err;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    err.swap(error_);
  }
  if (!err.empty()) throw InternalError("embree error during " + during + ": " + err);
}

// ---------------------------------------------------------------------------------------------
struct DropScene::Query {
  RTCIntersectContext context;  // first member: Embree hands the filter a pointer to it
  const DropScene* scene = nullptr;
  Eigen::Vector3d o, d;
  double t_min = 0;
  int skip_prim = -1;
  // Nearest crossing accepted so far (mutable: the filter receives a const context).
  mutable float best_t_float = std::numeric_limits<float>::infinity();
  mutable double best_t = 0;
  mutable int best_prim = -1;
};

DropScene::DropScene(const EmbreeDevice& device, const GlassPlane& plane, std::vector<PlacedDrop> drops,
                     CapGeometry geometry, int cap_segments)
    : device_(device), plane_(plane), drops_(std::move(drops)), geometry_(geometry) {
  WGS_CHECK(std::abs(plane_.water_normal.norm() - 1.0) < 1e-9);
  build_neighbors();
  build_footprint_grid();
  const int rings = std::max(2, cap_segments / 4);
  for (const PlacedDrop& p : drops_) {
    double r = p.sphere_radius;
    // A facet's vertices lie on the sphere; its points are at least R cos(edge angle) from the center.
    if (geometry_ == CapGeometry::kTriangles)
      r *= std::cos(std::max(2 * kPi / cap_segments, p.contact_angle_rad / rings));
    inside_radius_.push_back(r);
  }
  scene_ = rtcNewScene(device_.handle());
  device_.throw_if_error("rtcNewScene");
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_ROBUST);
  if (geometry_ == CapGeometry::kAnalytic)
    add_spheres();
  else
    add_triangles(cap_segments);
  rtcCommitScene(scene_);
  device_.throw_if_error("rtcCommitScene");
}

DropScene::~DropScene() {
  if (scene_) rtcReleaseScene(scene_);
}

void DropScene::build_neighbors() {
  const int n = int(drops_.size());
  neighbors_.assign(n, {});
  // Sweep along x: balls overlap only if their x intervals do.
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  auto lo = [&](int i) { return drops_[i].sphere_center.x() - drops_[i].sphere_radius; };
  std::sort(order.begin(), order.end(), [&](int a, int b) { return lo(a) < lo(b) || (lo(a) == lo(b) && a < b); });
  for (int ai = 0; ai < n; ++ai) {
    const int i = order[ai];
    const PlacedDrop& p = drops_[i];
    for (int bi = ai + 1; bi < n && lo(order[bi]) <= p.sphere_center.x() + p.sphere_radius; ++bi) {
      const int j = order[bi];
      const PlacedDrop& q = drops_[j];
      const double rr = p.sphere_radius + q.sphere_radius;
      if ((p.sphere_center - q.sphere_center).squaredNorm() < rr * rr) {
        neighbors_[i].push_back(j);
        neighbors_[j].push_back(i);
      }
    }
  }
  for (auto& v : neighbors_) std::sort(v.begin(), v.end());
}

void DropScene::build_footprint_grid() {
  plane_basis(plane_.water_normal, &grid_e1_, &grid_e2_);
  if (drops_.empty()) return;
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(kInf), hi = -lo;
  double max_a = 0;
  for (const PlacedDrop& p : drops_) {
    Eigen::Vector3d rel = p.base_center - plane_.point;
    Eigen::Vector2d c(rel.dot(grid_e1_), rel.dot(grid_e2_));
    lo = lo.cwiseMin(c - Eigen::Vector2d::Constant(p.base_radius));
    hi = hi.cwiseMax(c + Eigen::Vector2d::Constant(p.base_radius));
    max_a = std::max(max_a, p.base_radius);
  }
  const double extent = std::max(hi.x() - lo.x(), hi.y() - lo.y());
  // About one drop per cell for typical fields: a disk spans a few cells, a lookup tests few disks.
  grid_cell_ = std::max({max_a / 2, extent / 256, 1e-12});
  grid_lo_ = lo;
  grid_nx_ = std::max(1, int(std::ceil((hi.x() - lo.x()) / grid_cell_)));
  grid_ny_ = std::max(1, int(std::ceil((hi.y() - lo.y()) / grid_cell_)));
  grid_.assign(size_t(grid_nx_) * grid_ny_, {});
  for (int i = 0; i < int(drops_.size()); ++i) {
    const PlacedDrop& p = drops_[i];
    Eigen::Vector3d rel = p.base_center - plane_.point;
    Eigen::Vector2d c(rel.dot(grid_e1_), rel.dot(grid_e2_));
    int x0 = std::clamp(int((c.x() - p.base_radius - lo.x()) / grid_cell_), 0, grid_nx_ - 1);
    int x1 = std::clamp(int((c.x() + p.base_radius - lo.x()) / grid_cell_), 0, grid_nx_ - 1);
    int y0 = std::clamp(int((c.y() - p.base_radius - lo.y()) / grid_cell_), 0, grid_ny_ - 1);
    int y1 = std::clamp(int((c.y() + p.base_radius - lo.y()) / grid_cell_), 0, grid_ny_ - 1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) grid_[size_t(y) * grid_nx_ + x].push_back(i);
  }
}

bool DropScene::in_footprint(const Eigen::Vector3d& p) const {
  if (grid_.empty()) return false;
  Eigen::Vector3d rel = p - plane_.point;
  const double u = (rel.dot(grid_e1_) - grid_lo_.x()) / grid_cell_;
  const double v = (rel.dot(grid_e2_) - grid_lo_.y()) / grid_cell_;
  if (!(u >= 0 && v >= 0 && u < grid_nx_ && v < grid_ny_)) return false;
  for (int i : grid_[size_t(int(v)) * grid_nx_ + int(u)]) {
    const PlacedDrop& d = drops_[i];
    Eigen::Vector3d q = p - d.base_center;
    q -= q.dot(plane_.water_normal) * plane_.water_normal;
    if (q.squaredNorm() < d.base_radius * d.base_radius) return true;
  }
  return false;
}

bool DropScene::on_boundary(const Eigen::Vector3d& p, int drop) const {
  const double tol = geometry_ == CapGeometry::kAnalytic ? kAnalyticHeightTolerance : kTriangleHeightTolerance;
  if (plane_.height(p) < -tol) return false;
  for (int j : neighbors_[drop]) {
    const PlacedDrop& q = drops_[j];
    if ((p - q.sphere_center).squaredNorm() < inside_radius_[j] * inside_radius_[j] * (1 - kInsideRelTolerance))
      return false;
  }
  return true;
}

void DropScene::add_spheres() {
  RTCGeometry geom = rtcNewGeometry(device_.handle(), RTC_GEOMETRY_TYPE_SPHERE_POINT);
  device_.throw_if_error("rtcNewGeometry(sphere)");
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                                        4 * sizeof(float), drops_.size()));
  device_.throw_if_error("rtcSetNewGeometryBuffer(spheres)");
  for (size_t i = 0; i < drops_.size(); ++i) {
    v[4 * i + 0] = float(drops_[i].sphere_center.x());
    v[4 * i + 1] = float(drops_[i].sphere_center.y());
    v[4 * i + 2] = float(drops_[i].sphere_center.z());
    // Rounded up so float rounding never loses a crossing; the filter re-solves in double.
    v[4 * i + 3] = float(drops_[i].sphere_radius) * (1 + 1e-6f);
  }
  rtcSetGeometryIntersectFilterFunction(geom, &DropScene::filter);
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene_, geom);
  rtcReleaseGeometry(geom);
  device_.throw_if_error("building the sphere geometry");
}

void DropScene::add_triangles(int segments) {
  const int rings = std::max(2, segments / 4);
  std::vector<Eigen::Vector3f> verts;
  Eigen::Vector3d e1, e2;
  plane_basis(plane_.water_normal, &e1, &e2);
  for (int di = 0; di < int(drops_.size()); ++di) {
    const PlacedDrop& p = drops_[di];
    const int base = int(verts.size());
    // Apex, then rings at polar angles theta * k / rings about the water normal; the last ring is the
    // contact line on the glass.
    auto add = [&](const Eigen::Vector3d& dir) {
      verts.push_back((p.sphere_center + p.sphere_radius * dir).cast<float>());
      vertex_normals_.push_back(dir.cast<float>());
    };
    add(plane_.water_normal);
    for (int k = 1; k <= rings; ++k) {
      const double phi = p.contact_angle_rad * k / rings;
      for (int s = 0; s < segments; ++s) {
        const double a = 2 * kPi * s / segments;
        add(std::cos(phi) * plane_.water_normal + std::sin(phi) * (std::cos(a) * e1 + std::sin(a) * e2));
      }
    }
    auto ring_v = [&](int k, int s) { return base + 1 + (k - 1) * segments + (s % segments); };
    for (int s = 0; s < segments; ++s) {
      triangles_.emplace_back(base, ring_v(1, s), ring_v(1, s + 1));
      prim_drop_.push_back(di);
    }
    for (int k = 1; k < rings; ++k) {
      for (int s = 0; s < segments; ++s) {
        triangles_.emplace_back(ring_v(k, s), ring_v(k + 1, s), ring_v(k + 1, s + 1));
        triangles_.emplace_back(ring_v(k, s), ring_v(k + 1, s + 1), ring_v(k, s + 1));
        prim_drop_.push_back(di);
        prim_drop_.push_back(di);
      }
    }
  }
  RTCGeometry geom = rtcNewGeometry(device_.handle(), RTC_GEOMETRY_TYPE_TRIANGLE);
  device_.throw_if_error("rtcNewGeometry(triangle)");
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                         3 * sizeof(float), verts.size()));
  auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                            3 * sizeof(unsigned), triangles_.size()));
  device_.throw_if_error("rtcSetNewGeometryBuffer(triangles)");
  for (size_t i = 0; i < verts.size(); ++i)
    for (int c = 0; c < 3; ++c) vb[3 * i + c] = verts[i][c];
  for (size_t i = 0; i < triangles_.size(); ++i)
    for (int c = 0; c < 3; ++c) ib[3 * i + c] = unsigned(triangles_[i][c]);
  rtcSetGeometryIntersectFilterFunction(geom, &DropScene::filter);
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene_, geom);
  rtcReleaseGeometry(geom);
  device_.throw_if_error("building the triangle geometry");
}

std::optional<double> DropScene::refine_sphere_t(const Eigen::Vector3d& o, const Eigen::Vector3d& d, int drop,
                                                 double t_approx) const {
  const PlacedDrop& p = drops_[drop];
  const Eigen::Vector3d oc = o - p.sphere_center;
  const double b = oc.dot(d);
  const double len = oc.norm();
  const double c = (len - p.sphere_radius) * (len + p.sphere_radius);
  double disc = b * b - c;
  // Embree (float) reported a crossing: a slightly negative discriminant is a tangent ray.
  if (disc < 0) {
    if (disc < -1e-6 * (b * b + std::abs(c) + 1e-30)) return std::nullopt;
    disc = 0;
  }
  const double sq = std::sqrt(disc);
  // Stable roots (Numerical Recipes 5.6): q = -(b + sign(b) sq), roots q and c / q.
  const double q = -(b + std::copysign(sq, b));
  double t1 = q, t2 = q != 0 ? c / q : 0.0;
  return std::abs(t1 - t_approx) <= std::abs(t2 - t_approx) ? t1 : t2;
}

void DropScene::filter(const RTCFilterFunctionNArguments* args) {
  const auto* q = reinterpret_cast<const Query*>(args->context);
  const DropScene& s = *q->scene;
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] != -1) continue;
    const unsigned prim = RTCHitN_primID(args->hit, args->N, i);
    const double t_float = RTCRayN_tfar(args->ray, args->N, i);
    int drop;
    double t;
    if (s.geometry_ == CapGeometry::kAnalytic) {
      drop = int(prim);
      // Cheap rejection of crossings far below the glass (the lower part of a flat drop's sphere)
      // before the double-precision re-solve; the margin covers float error at the sphere's scale.
      const Eigen::Vector3d p_float = q->o + t_float * q->d;
      if (s.plane_.height(p_float) < -1e-5 * (s.drops_[drop].sphere_radius + p_float.norm())) {
        args->valid[i] = 0;
        continue;
      }
      std::optional<double> r = s.refine_sphere_t(q->o, q->d, drop, t_float);
      if (!r) {
        args->valid[i] = 0;
        continue;
      }
      t = *r;
    } else {
      if (int(prim) == q->skip_prim) {
        args->valid[i] = 0;
        continue;
      }
      drop = s.prim_drop_[prim];
      t = t_float;
    }
    if (!(t > q->t_min) || !s.on_boundary(q->o + t * q->d, drop)) {
      args->valid[i] = 0;
      continue;
    }
    // Embree keeps the nearest accepted crossing; remember its double-precision distance.
    if (t_float <= q->best_t_float) {
      q->best_t_float = t_float;
      q->best_t = t;
      q->best_prim = int(prim);
    }
  }
}

std::optional<CapHit> DropScene::intersect_boundary(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                                    double t_min, double t_max, int skip_prim,
                                                    int* prim_out) const {
  if (drops_.empty()) return std::nullopt;
  Query q;
  rtcInitIntersectContext(&q.context);
  q.scene = this;
  q.o = o;
  q.d = d;
  q.t_min = t_min;
  q.skip_prim = skip_prim;
  RTCRayHit rh;
  rh.ray.org_x = float(o.x());
  rh.ray.org_y = float(o.y());
  rh.ray.org_z = float(o.z());
  rh.ray.dir_x = float(d.x());
  rh.ray.dir_y = float(d.y());
  rh.ray.dir_z = float(d.z());
  rh.ray.tnear = 0.f;  // t_min is enforced in double by the filter
  rh.ray.tfar = std::isfinite(t_max) ? float(t_max) * (1 + 1e-6f) : std::numeric_limits<float>::infinity();
  rh.ray.time = 0.f;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene_, &q.context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  CapHit hit;
  const unsigned prim = rh.hit.primID;
  if (prim_out) *prim_out = int(prim);
  if (geometry_ == CapGeometry::kAnalytic) {
    hit.drop = int(prim);
    WGS_CHECK_EQ(q.best_prim, hit.drop);  // the filter accepted this very crossing
    hit.t = q.best_t;
    hit.normal = (o + hit.t * d - drops_[hit.drop].sphere_center).normalized();
  } else {
    hit.drop = prim_drop_[prim];
    hit.t = rh.ray.tfar;
    const Eigen::Vector3i& tri = triangles_[prim];
    const float u = rh.hit.u, v = rh.hit.v;
    Eigen::Vector3f n = (1 - u - v) * vertex_normals_[tri[0]] + u * vertex_normals_[tri[1]] +
                        v * vertex_normals_[tri[2]];
    hit.normal = n.cast<double>().normalized();
  }
  if (!(hit.t <= t_max) || !hit.normal.allFinite()) return std::nullopt;
  return hit;
}

// ---------------------------------------------------------------------------------------------
namespace {

// One event of a ray in the glass slab (heights -h..0 below the water plane), or entering it from the
// dry side: moves *o to the face it meets and refracts (or totally reflects) *d there. Returns false
// when the ray runs parallel to the faces (it never leaves: numerically lost).
bool slab_event(const GlassPlane& plane, const DropScene& scene, double h, double eta_glass, double eta_water,
                Eigen::Vector3d* o, Eigen::Vector3d* d, bool* in_glass, bool* in_water, double* w,
                double* w_camera, int* bounces, PathResult* res, std::vector<PathEvent>* events) {
  const double height = plane.height(*o), dn = d->dot(plane.water_normal);
  if (std::abs(dn) <= kParallelCos) return false;
  // Entering from the dry side meets the inner face; inside, the ray heads for one of the two faces.
  const bool outer = *in_glass && dn > 0;
  const double t = outer ? -height / dn : (-h - height) / dn;
  const Eigen::Vector3d p = *o + std::max(t, 0.0) * *d;
  const bool into_water = outer && scene.in_footprint(p);
  const double eta_i = *in_glass ? eta_glass : 1.0;
  const double eta_t = *in_glass ? (into_water ? eta_water : 1.0) : eta_glass;
  const Eigen::Vector3d n_facing = dn > 0 ? Eigen::Vector3d(-plane.water_normal) : plane.water_normal;
  const double cos_i = std::clamp(-d->dot(n_facing), 0.0, 1.0);
  const std::optional<Eigen::Vector3d> refracted = refract(*d, n_facing, eta_i, eta_t);
  PathEvent e;
  e.point = p;
  e.normal = n_facing;
  e.d_in = *d;
  e.eta_i = eta_i;
  e.eta_t = eta_t;
  e.through_base = into_water;
  e.glass_face = !into_water;
  if (!refracted) {
    e.total_internal_reflection = true;
    e.reflectance = 1;
    *d = reflect(*d, n_facing).normalized();
    ++*bounces;
    ++res->internal_reflections;
  } else {
    // A path that has not met water yet crosses clean glass: its reflections are in the clean image.
    const bool counted = res->touched_water || into_water;
    const double reflectance = counted ? fresnel_dielectric(cos_i, eta_i, eta_t) : 0.0;
    e.reflectance = reflectance;
    // As at a dry-side base (trace_path): reflected light heading back meets the camera.
    if (into_water && reflect(*d, n_facing).z() <= kMinForwardZ) *w_camera += *w * reflectance;
    *w *= 1 - reflectance;
    *d = *refracted;
    *in_water = into_water;
    *in_glass = !*in_glass;
    if (into_water) res->touched_water = true;
  }
  e.d_out = *d;
  if (events) events->push_back(e);
  *o = p;
  return true;
}

}  // namespace

PathResult trace_path(const DropScene& scene, const Eigen::Vector3d& o0, const Eigen::Vector3d& d0,
                      const TraceOptions& options, std::vector<PathEvent>* events) {
  PathResult res;
  const GlassPlane& plane = scene.plane();
  const double eta_water = options.refractive_index;
  Eigen::Vector3d o = o0, d = d0.normalized();
  double w = 1;  // weight of the followed path; the rest went to the environment or the camera
  double w_camera = 0;  // light sent back towards the camera: reflected from the dry side, or exiting backwards
  bool in_water = false;
  const double h_glass = options.glass_thickness_m, eta_glass = options.glass_refractive_index;
  bool in_glass = false;  // inside the slab (h_glass > 0 only)
  int skip_prim = -1, bounces = 0;
  // Every boundary event either changes medium or counts a bounce, so this only stops a ray that
  // keeps crossing overlapping drops.
  const int max_events = 4 * options.max_bounces + 64;
  for (int ev = 0;; ++ev) {
    if (ev >= max_events) {
      w = 0;
      break;
    }
    // Self-crossings at the current point are excluded below this distance (double rounding of a
    // point ~0.03-1 m from the camera is ~1e-16 m; real crossings are >= nanometers apart).
    const double t_eps = 1e-12 + 1e-10 * o.norm();
    const double dn = d.dot(plane.water_normal);
    if (h_glass > 0 && (in_glass || (!in_water && plane.height(o) < -0.5 * h_glass && dn > kParallelCos))) {
      if (!slab_event(plane, scene, h_glass, eta_glass, eta_water, &o, &d, &in_glass, &in_water, &w, &w_camera,
                      &bounces, &res, events))
        break;
      skip_prim = -1;
      if (bounces > options.max_bounces) {
        w = 0;
        break;
      }
      continue;
    }
    double t_plane = kInf;
    if (std::abs(dn) > kParallelCos) {
      const double t = -plane.height(o) / dn;
      if (t > t_eps) t_plane = t;
    }
    int prim = -1;
    std::optional<CapHit> cap;
    bool base_event = false;
    if (!in_water && t_plane < kInf && plane.height(o) < 0) {
      // From the dry side no cap lies before the glass: the footprint decides without Embree.
      base_event = scene.in_footprint(o + t_plane * d);
      if (!base_event) {
        cap = scene.intersect_boundary(o, d, t_eps, kInf, skip_prim, &prim);
        ++res.boundary_queries;
      }
    } else {
      cap = scene.intersect_boundary(o, d, t_eps, kInf, skip_prim, &prim);
      ++res.boundary_queries;
      if (t_plane < kInf && (!cap || t_plane < cap->t))
        base_event = in_water || scene.in_footprint(o + t_plane * d);
    }
    if (!base_event && !cap) break;
    const double t = base_event ? t_plane : cap->t;
    const Eigen::Vector3d p = o + t * d;
    const Eigen::Vector3d n_out = base_event ? Eigen::Vector3d(-plane.water_normal) : cap->normal;
    const Eigen::Vector3d n_facing = d.dot(n_out) < 0 ? n_out : Eigen::Vector3d(-n_out);
    // With a slab, water leaves through its base into the glass (the thin glass: straight into air).
    const bool into_glass = h_glass > 0 && base_event && in_water;
    const double eta_i = in_water ? eta_water : 1.0, eta_t = in_water ? (into_glass ? eta_glass : 1.0) : eta_water;
    const double cos_i = std::clamp(-d.dot(n_facing), 0.0, 1.0);
    const double reflectance = fresnel_dielectric(cos_i, eta_i, eta_t);
    std::optional<Eigen::Vector3d> refracted = refract(d, n_facing, eta_i, eta_t);
    PathEvent e;
    e.point = p;
    e.normal = n_facing;
    e.d_in = d;
    e.eta_i = eta_i;
    e.eta_t = eta_t;
    e.through_base = base_event;
    e.drop = base_event ? -1 : cap->drop;
    res.touched_water = true;
    if (!refracted) {
      e.total_internal_reflection = true;
      e.reflectance = 1;
      d = reflect(d, n_facing).normalized();
      ++bounces;
      ++res.internal_reflections;
    } else {
      e.reflectance = reflectance;
      // A reflection from the dry side leaves the drop at once: when it heads back (towards the camera's
      // side of the image plane) it meets the camera. Reflections inside the water are not followed.
      if (!in_water && reflect(d, n_facing).z() <= kMinForwardZ) w_camera += w * reflectance;
      w *= 1 - reflectance;
      d = *refracted;
      in_water = !in_water;
      in_glass = into_glass;
    }
    e.d_out = d;
    if (events) events->push_back(e);
    o = p;
    skip_prim = base_event ? -1 : prim;
    if (bounces > options.max_bounces) {
      w = 0;
      break;
    }
  }
  if (in_water || in_glass) {  // lost inside (numerically) or trapped: no direction to look up
    w = 0;
  }
  res.exit_direction = d;
  if (!res.touched_water) {
    res.scene_weight = 1;
    return res;
  }
  if (w > 0 && d.z() <= kMinForwardZ) {  // leaves backwards: towards the camera
    w_camera += w;
    w = 0;
  }
  // Everything not followed (Fresnel reflections, cut paths) is the exact complement of w.
  res.scene_weight = std::clamp(w, 0.0, 1.0);
  res.camera_weight = std::clamp(w_camera, 0.0, 1.0 - res.scene_weight);
  res.environment_weight = 1.0 - res.scene_weight - res.camera_weight;
  return res;
}

}  // namespace weathergs::generator::lens
