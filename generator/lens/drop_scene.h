// Embree 3 geometry of the drops of one view, and the light path through them.
//
// The water body is the union of the drops' balls cut by the glass plane. Embree finds candidate
// crossings of its curved boundary (a sphere per drop, RTC_GEOMETRY_TYPE_SPHERE_POINT, or
// triangulated caps); an intersection filter keeps a crossing only where it lies on the water side
// of the glass and outside every other drop's ball, so overlapping drops merge into one body.
// Sphere crossings are re-solved in double precision, which keeps flat caps (sphere radius up to
// meters for a millimeter drop) and grazing rim rays stable.
#pragma once

#include <embree3/rtcore.h>

#include <Eigen/Core>
#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "generator/lens/drops.h"
#include "generator/lens/lens_spec.h"
#include "generator/lens/optics.h"

namespace weathergs::generator::lens {

// An Embree device whose errors become exceptions: the error callback records the message and every
// wrapper call ends with throw_if_error(), which throws InternalError naming the failed step.
class EmbreeDevice {
 public:
  EmbreeDevice();
  ~EmbreeDevice();
  EmbreeDevice(const EmbreeDevice&) = delete;
  EmbreeDevice& operator=(const EmbreeDevice&) = delete;

  RTCDevice handle() const { return device_; }
  void throw_if_error(const std::string& during) const;
  // Devices created by this process so far (tests check that no droplets means no device).
  static int64_t num_created();

 private:
  static void on_error(void* self, RTCError code, const char* message);
  RTCDevice device_ = nullptr;
  mutable std::mutex mutex_;
  mutable std::string error_;
};

// A crossing of the water body's curved boundary.
struct CapHit {
  double t = 0;
  int drop = -1;                                      // index into DropScene::drops()
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();   // unit, pointing out of the water
};

class DropScene {
 public:
  DropScene(const EmbreeDevice& device, const GlassPlane& plane, std::vector<PlacedDrop> drops,
            CapGeometry geometry, int cap_segments);
  ~DropScene();
  DropScene(const DropScene&) = delete;
  DropScene& operator=(const DropScene&) = delete;

  const std::vector<PlacedDrop>& drops() const { return drops_; }
  const GlassPlane& plane() const { return plane_; }
  CapGeometry geometry() const { return geometry_; }

  // Nearest boundary crossing along o + t d with t in (t_min, t_max). `skip_prim` is the Embree
  // primitive the ray starts on (triangles only; -1 for none).
  std::optional<CapHit> intersect_boundary(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
                                           double t_max, int skip_prim = -1, int* prim_out = nullptr) const;
  // Whether a point of the glass plane lies under some drop (inside its base disk).
  bool in_footprint(const Eigen::Vector3d& p) const;
  // Whether the crossing of drop i's surface at p belongs to the water body's boundary.
  bool on_boundary(const Eigen::Vector3d& p, int drop) const;

  // Embree filter and double-precision sphere re-solve (public for the filter callback only).
  struct Query;
  static void filter(const RTCFilterFunctionNArguments* args);
  std::optional<double> refine_sphere_t(const Eigen::Vector3d& o, const Eigen::Vector3d& d, int drop,
                                        double t_approx) const;

 private:
  void build_neighbors();
  void build_footprint_grid();
  void add_spheres();
  void add_triangles(int segments);

  const EmbreeDevice& device_;
  GlassPlane plane_;
  std::vector<PlacedDrop> drops_;
  CapGeometry geometry_;
  RTCScene scene_ = nullptr;
  std::vector<std::vector<int>> neighbors_;  // drops whose balls overlap, per drop
  // Radius within which a point counts as inside a drop (for the union): the sphere radius, or for
  // triangulated caps the radius of the facets' inscribed sphere, so that seams between merged
  // faceted drops leave no gap.
  std::vector<double> inside_radius_;
  std::vector<int> prim_drop_;               // triangles: primitive -> drop
  std::vector<Eigen::Vector3f> vertex_normals_;
  std::vector<Eigen::Vector3i> triangles_;
  // Footprint grid on the glass plane: 2D basis, origin, cell size, cells -> drops.
  Eigen::Vector3d grid_e1_, grid_e2_;
  Eigen::Vector2d grid_lo_ = Eigen::Vector2d::Zero();
  double grid_cell_ = 1;
  int grid_nx_ = 0, grid_ny_ = 0;
  std::vector<std::vector<int>> grid_;
};

// One interface event of a traced path (tests check Snell's law and energy on these).
struct PathEvent {
  Eigen::Vector3d point, normal;  // normal faces the incoming ray
  Eigen::Vector3d d_in, d_out;
  double eta_i = 1, eta_t = 1;
  double reflectance = 0;          // Fresnel; 1 under total internal reflection
  bool total_internal_reflection = false;
  bool through_base = false;       // at the flat base (through the thin glass) rather than the cap
  bool glass_face = false;         // slab only: at a face of the glass where no drop sits
  int drop = -1;
};

struct PathResult {
  bool touched_water = false;
  Eigen::Vector3d exit_direction = Eigen::Vector3d::UnitZ();  // camera frame, unit
  double scene_weight = 0;        // of the scene radiance along exit_direction
  double environment_weight = 0;  // of the environment radiance (reflections, paths cut short)
  double camera_weight = 0;       // of light sent back towards the camera (see trace_path)
  int internal_reflections = 0;
  int boundary_queries = 0;  // Embree ray casts made for this path
};

struct TraceOptions {
  double refractive_index = kWaterRefractiveIndex;
  int max_bounces = 4;
  // The glass the drops sit on: a slab of this thickness on the dry side of the water plane (0: the
  // thin glass, which changes no direction and traps nothing).
  double glass_thickness_m = 0;
  double glass_refractive_index = kCrownGlassRefractiveIndex;
};

// Follows a camera ray (origin o, unit direction d, camera frame) through the water body: refraction
// and Fresnel at every boundary, total internal reflection up to max_bounces times. With
// glass_thickness_m 0 the glass is thin (parallel interfaces conserve n sin(theta): it changes no
// direction, and a water-air base stands for water-glass-air). With a slab, rays refract into it and
// out of it, shift sideways, and light that total internal reflection traps in the glass (it meets
// its dry faces beyond the critical angle) stays there until it finds a drop's base or the bounces
// run out. The glass's own reflections on a path that never touched water belong to the clean image
// and are not counted. Light
// reflected at a boundary and not followed (Fresnel reflections, paths cut at max_bounces) takes the
// environment radiance, except light sent back towards the camera (a reflection from the dry side
// heading backwards, a path leaving the water backwards): camera_weight, which meets the camera
// itself. scene_weight + environment_weight + camera_weight = 1 for a path that touched water.
PathResult trace_path(const DropScene& scene, const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                      const TraceOptions& options, std::vector<PathEvent>* events = nullptr);

}  // namespace weathergs::generator::lens
