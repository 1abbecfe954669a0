#include "generator/stages.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/constants.h"
#include "core/dataset_layout.h"
#include "core/error.h"
#include "core/parallel.h"

namespace weathergs::generator {

namespace {
// Work items of the particle stage are (class, cell) pairs, processed in fixed chunks.
constexpr int64_t kCellsPerChunk = 64;
// Refuse views that would enumerate more cells than this (memory and time stay bounded; raise
// render.visibility_cutoff or lower render.max_distance_m).
constexpr int64_t kMaxCellsPerClass = 20'000'000;
// Gusts are bounded at this many standard deviations per component (3: a particle faster than that
// relative to its frame at a frustum border may be missed, probability ~1e-3 per such particle).
constexpr double kGustSigmas = 3.0;
}  // namespace

const char* const kManifestHeader =
    "id,diameter_mm,visual_diameter_mm,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,camera_z_m,visible\n";

void FogStage::run(WeatherView& v) const {
  const Camera& cam = v.camera;
  Image t(cam.width, cam.height, 1, ColorSpace::kLinear);
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const double z = v.depth.at(x, y);
      double tr = 1.0;
      if (is_background_depth(z)) {
        tr = beta_ > 0 ? 0.0 : 1.0;
      } else if (z > 0) {
        const double nx = (x + 0.5 - cam.cx) / cam.fx, ny = (y + 0.5 - cam.cy) / cam.fy;
        tr = std::exp(-beta_ * z * std::sqrt(nx * nx + ny * ny + 1.0));  // ray length from planar z
      }
      t.at(x, y) = float(tr);
      for (int c = 0; c < 3; ++c) {
        float& r = v.radiance.at(x, y, c);
        r = float(r * tr + airlight_[c] * (1.0 - tr));
      }
    }
  }
  v.fog.beta_per_m = beta_;
  v.fog.airlight = airlight_;
  v.layers["fog_transmittance"] = std::move(t);
}

ParticleStage::ParticleStage(const ParticleEffectSpec& effect, const RenderOptions& render, uint64_t seed,
                             bool manifest, std::optional<SunLight> sun)
    : field_(effect.species, seed), appearance_(effect.appearance), render_(render), manifest_(manifest), sun_(sun) {}

double relative_speed_bound_m_s(const ParticleField& field, int k) {
  const SizeClass& cls = field.classes()[size_t(k)];
  const SpeciesOptions& o = field.options();
  return std::abs(o.fall_speed_m_s(cls.hi_mm) - o.fall_speed_m_s(cls.lo_mm)) +
         kGustSigmas * std::sqrt(3.0) * o.wind.turbulence_rms_m_s +
         (o.species == Species::kSnow ? o.flutter_amplitude_m[1] * 2 * kPi * o.flutter_frequency_hz[1] : 0.0);
}

std::vector<CellIndex> visible_cells(const ParticleField& field, int k, const Camera& cam, double near,
                                     double distance, double extra_margin) {
  const SizeClass& cls = field.classes()[size_t(k)];
  const double s = cls.cell_m;
  const double t0 = cam.time_s, exposure = cam.exposure_s;
  const Eigen::Vector3d u = field.frame_velocity(k);
  // Slack: motion relative to the frame over the exposure, plus the particle's own size.
  const double margin =
      relative_speed_bound_m_s(field, k) * exposure + 2 * cls.max_visual_radius_m + extra_margin + 1e-3;
  // Frustum planes in camera space, inward unit normals: n . p_camera + offset >= 0.
  struct Plane {
    Eigen::Vector3d n;
    double offset;
  };
  std::vector<Plane> planes = {
      {Eigen::Vector3d(1, 0, cam.cx / cam.fx), 0},
      {Eigen::Vector3d(-1, 0, (cam.width - cam.cx) / cam.fx), 0},
      {Eigen::Vector3d(0, 1, cam.cy / cam.fy), 0},
      {Eigen::Vector3d(0, -1, (cam.height - cam.cy) / cam.fy), 0},
      {Eigen::Vector3d(0, 0, 1), -near},
      {Eigen::Vector3d(0, 0, -1), distance}};
  const Eigen::Matrix3d rot = cam.rotation();
  const Eigen::Vector3d trans = cam.translation();
  // In world space: n_w . p + (n . t + offset) >= -margin.
  for (Plane& p : planes) {
    const double len = p.n.norm();
    p.n /= len;
    p.offset /= len;
    p.offset += p.n.dot(trans) + margin;
    p.n = rot.transpose() * p.n;
  }
  // World AABB of the frustum corners, at the shutter's open and close in the frame of class k.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
  for (double z : {near, distance})
    for (double px : {0.0, double(cam.width)})
      for (double py : {0.0, double(cam.height)}) {
        const Eigen::Vector3d pw = cam.unproject(Eigen::Vector2d(px, py), z);
        for (double t : {t0, t0 + exposure}) {
          lo = lo.cwiseMin(pw - u * t);
          hi = hi.cwiseMax(pw - u * t);
        }
      }
  lo.array() -= margin;
  hi.array() += margin;
  CellIndex c0, c1;
  for (int a = 0; a < 3; ++a) {
    c0[a] = int64_t(std::floor(lo[a] / s));
    c1[a] = int64_t(std::floor(hi[a] / s));
  }
  const double count = double(c1.x() - c0.x() + 1) * double(c1.y() - c0.y() + 1) * double(c1.z() - c0.z() + 1);
  if (count > double(kMaxCellsPerClass))
    throw InputError("view '" + cam.name + "'",
                     "the visible particle volume needs " + std::to_string(int64_t(count)) +
                         " cells for one size class; raise render.visibility_cutoff or lower render.max_distance_m");
  std::vector<CellIndex> cells;
  const Eigen::Vector3d half = Eigen::Vector3d::Constant(0.5 * s);
  const Eigen::Vector3d sweep = 0.5 * u * exposure;  // the box moves by u * exposure while open
  for (int64_t z = c0.z(); z <= c1.z(); ++z)
    for (int64_t y = c0.y(); y <= c1.y(); ++y)
      for (int64_t x = c0.x(); x <= c1.x(); ++x) {
        const Eigen::Vector3d center = (Eigen::Vector3d(double(x), double(y), double(z)) * s) + half + u * t0 + sweep;
        const Eigen::Vector3d ext = half + sweep.cwiseAbs();
        bool inside = true;
        for (const Plane& p : planes)
          if (p.n.dot(center) + p.n.cwiseAbs().dot(ext) + p.offset < 0) {
            inside = false;
            break;
          }
        if (inside) cells.push_back(CellIndex(x, y, z));
      }
  return cells;
}

double population_distance_m(const ParticleField& field, int k, const RenderView& view, double opacity,
                             const RenderOptions& options) {
  const SizeClass& cls = field.classes()[size_t(k)];
  const Camera& cam = view.camera;
  const double f = view.f_px(), r = cls.max_visual_radius_m, a0 = opacity;
  const double still = visibility_distance_m(f, r, a0, options);
  const double exposure = cam.exposure_s;
  if (!(exposure > 0)) return still;
  // Slowest image motion over the frustum: |U x d| over a 9 x 9 grid of pixel directions, 0 if the
  // frame velocity (or its opposite) points into the image; minus a 3-sigma bound of the particles'
  // own motion relative to the frame (fall-speed spread, gusts, flutter).
  const Eigen::Vector3d u = field.frame_velocity(k);
  double v_perp = 1e300;
  if (u.norm() > 0) {
    const Eigen::Vector3d uc = cam.rotation() * u;
    for (const Eigen::Vector3d& dir : {uc, Eigen::Vector3d(-uc)})
      if (dir.z() > 0) {
        const Eigen::Vector2d px = cam.project_camera(dir);
        if (px.x() >= 0 && px.x() <= cam.width && px.y() >= 0 && px.y() <= cam.height) v_perp = 0;
      }
    for (int i = 0; i <= 8; ++i)
      for (int j = 0; j <= 8; ++j) {
        const Eigen::Vector3d d = cam.ray_direction_world(Eigen::Vector2d(cam.width * i / 8.0, cam.height * j / 8.0));
        v_perp = std::min(v_perp, u.cross(d).norm());
      }
  } else {
    v_perp = 0;
  }
  const double own = relative_speed_bound_m_s(field, k);
  // 0.9: the grid may miss the exact minimum between its points.
  const double vp = 0.9 * v_perp - own;
  if (!(vp > 0)) return still;
  // Point kernel: peak <= 1.5 m / L with m = pi a0 (f r / z)^2 and L = f vp T / z.
  const double d_point = 1.5 * kPi * f * r * r * a0 / (vp * exposure * options.visibility_cutoff);
  // Disk kernel (R >= 0.5 px, z <= 2 f r): peak <= a0 2R / L = 2 a0 r / (vp T), for any z.
  const double d_disk = 2 * a0 * r / (vp * exposure) >= options.visibility_cutoff ? 2 * f * r : 0.0;
  return std::min(still, std::max(d_point, d_disk));
}

void ParticleStage::run(WeatherView& v) const {
  const Camera& cam = v.camera;
  const std::string species = to_string(field_.options().species);
  RenderView view;
  view.camera = cam;
  view.depth = &v.depth;
  if (render_.defocus) view.lens = thin_lens_of(cam);
  const double opacity = field_.options().opacity;
  const std::vector<double> times = path_sample_times(render_, cam.time_s, cam.exposure_s);

  struct Item {
    int k;
    CellIndex cell;
  };
  std::vector<Item> items;
  for (int k = 0; k < int(field_.classes().size()); ++k) {
    const double d = population_distance_m(field_, k, view, opacity, render_);
    if (!(d > render_.near_m)) continue;
    // A defocused particle just outside the frustum can blur into the image: its circle of
    // confusion, in world units at depth z, is A |z - s| / (2 (s - f)) (at most this over [0, d]).
    double blur_m = 0;
    if (view.lens)
      blur_m = 0.5 * view.lens->aperture_m * std::max(view.lens->focus_m, d - view.lens->focus_m) /
               (view.lens->focus_m - view.lens->focal_length_m);
    for (const CellIndex& c : visible_cells(field_, k, cam, render_.near_m, d, blur_m)) items.push_back({k, c});
  }
  const int64_t n_chunks = num_chunks(0, int64_t(items.size()), kCellsPerChunk);
  std::vector<SplatList> chunk_splats(static_cast<size_t>(n_chunks));
  std::vector<std::vector<Particle>> chunk_particles(static_cast<size_t>(n_chunks));
  std::vector<int64_t> chunk_generated(size_t(n_chunks), 0);
  parallel_for_chunks(0, int64_t(items.size()), kCellsPerChunk, [&](int64_t chunk, int64_t lo, int64_t hi) {
    std::vector<Particle> cell;
    std::vector<Eigen::Vector3d> pos(times.size());
    std::vector<ParticleState> st(times.size());
    SplatList& out = chunk_splats[size_t(chunk)];
    for (int64_t i = lo; i < hi; ++i) {
      cell.clear();
      field_.cell_particles(items[size_t(i)].k, items[size_t(i)].cell, &cell);
      chunk_generated[size_t(chunk)] += int64_t(cell.size());
      for (const Particle& p : cell) {
        field_.states(p, times.data(), int(times.size()), cam.time_s, st.data());
        for (size_t j = 0; j < times.size(); ++j) pos[j] = st[j].p_world;
        const int source = int(chunk_particles[size_t(chunk)].size());
        if (add_splat(view, render_, pos.data(), int(pos.size()), p.visual_radius_m, opacity, source, &out))
          chunk_particles[size_t(chunk)].push_back(p);
      }
    }
  });
  // Concatenate in chunk order; sources become global particle indices.
  SplatList splats;
  std::vector<Particle> particles;
  int64_t generated = 0;
  for (int64_t c = 0; c < n_chunks; ++c) {
    const size_t first_splat = splats.splats.size();
    splats.append(chunk_splats[size_t(c)]);
    for (size_t i = first_splat; i < splats.splats.size(); ++i) splats.splats[i].source += int(particles.size());
    particles.insert(particles.end(), chunk_particles[size_t(c)].begin(), chunk_particles[size_t(c)].end());
    generated += chunk_generated[size_t(c)];
    chunk_splats[size_t(c)] = SplatList();
  }
  std::optional<ParticleRadianceGrid> optics;
  if (appearance_.shading == ParticleShading::kOptics && !splats.splats.empty()) {
    const ViewEnvironment environment(cam, v.clean, v.environment.sky);
    optics.emplace(environment, cam,
                   field_.options().species == Species::kRain ? ParticleOptics::kWaterSphere : ParticleOptics::kLambertSphere,
                   appearance_.albedo, sun_ ? &*sun_ : nullptr);
  }
  shade_splats(v.environment, optics ? &*optics : nullptr, v.fog, appearance_, &splats);
  const ParticleRaster raster = rasterize_splats(view, splats, render_);
  composite_particles(raster, &v.radiance);
  for (size_t p = 0; p < raster.alpha.num_pixels(); ++p)
    v.particle_alpha.data[p] = 1.0f - (1.0f - v.particle_alpha.data[p]) * (1.0f - raster.alpha.data[p]);
  v.has_particles = true;
  v.layers[species + "_alpha"] = raster.alpha;
  v.layers[species + "_radiance"] = raster.radiance;  // with the alpha: this stage's layer, alpha (L - below), in float

  int64_t visible = 0;
  for (uint8_t b : raster.visible) visible += b;
  v.counters[species + ".cells"] += int64_t(items.size());
  v.counters[species + ".particles_generated"] += generated;
  v.counters[species + ".particles_drawn"] += int64_t(particles.size());
  v.counters[species + ".particles_visible"] += visible;
  if (manifest_) {
    std::string csv = kManifestHeader;
    char line[512];
    for (size_t i = 0; i < particles.size(); ++i) {
      const Particle& p = particles[i];
      const ParticleState s = field_.state(p, cam.time_s, cam.time_s);
      const double z = cam.to_camera(s.p_world).z();
      std::snprintf(line, sizeof(line), "%s,%.6g,%.6g,%.9g,%.9g,%.9g,%.6g,%.6g,%.6g,%.6g,%d\n",
                    p.id.to_string().c_str(), p.diameter_mm, 2000.0 * p.visual_radius_m, s.p_world.x(),
                    s.p_world.y(), s.p_world.z(), s.v_world.x(), s.v_world.y(), s.v_world.z(), z,
                    int(raster.visible[i]));
      csv += line;
    }
    v.texts["particles_" + species] = std::move(csv);
  }
}

}  // namespace weathergs::generator
