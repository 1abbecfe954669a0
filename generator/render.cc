#include "generator/render.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <opencv2/imgproc.hpp>

#include "core/constants.h"
#include "core/error.h"
#include "core/parallel.h"

namespace weathergs::generator {

const char* to_string(ParticleShading shading) {
  return shading == ParticleShading::kOptics ? "optics" : "weighted";
}

const char* to_string(StreakMode mode) { return mode == StreakMode::kAnalytic ? "analytic" : "time_samples"; }

namespace {
constexpr int kBandRows = 8;  // rows per band of the parallel rasterizer
// Subdivision of a streak's straight pieces for perspective (add_splat): the largest error, in
// pixels, of constant image speed at a piece's middle time (a tenth of a pixel, 20x below the 2 px
// streak-extent aim of the Cycles validation; benchmarks/README.md).
constexpr double kPerspectiveTolerancePx = 0.1;
constexpr int kMaxPerspectivePieces = 64;

struct PixelAlpha {
  int pixel;
  float alpha;
};

// Liang-Barsky: the part [*u0, *u1] of p0 + u (p1 - p0), u in [0, 1], inside [x0, x1] x [y0, y1].
bool clip_segment(double px, double py, double dx, double dy, double x0, double x1, double y0, double y1,
                  double* u0, double* u1) {
  double lo = 0, hi = 1;
  const double p[4] = {-dx, dx, -dy, dy};
  const double q[4] = {px - x0, x1 - px, py - y0, y1 - py};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0) {
      if (q[i] < 0) return false;
      continue;
    }
    const double r = q[i] / p[i];
    if (p[i] < 0) lo = std::max(lo, r);
    else hi = std::min(hi, r);
  }
  if (lo > hi) return false;
  *u0 = lo;
  *u1 = hi;
  return true;
}

// Point kernel: the primitive's mass spread by the exact length of the segment inside each pixel.
void raster_point(const SplatPrimitive& pr, int width, int row0, int row1, const Image& depth,
                  std::vector<PixelAlpha>* out) {
  const double mass = double(pr.a0) * kPi * double(pr.radius_px) * pr.radius_px * pr.weight;
  const double dx = double(pr.x1) - pr.x0, dy = double(pr.y1) - pr.y0;
  double ua, ub;
  if (!clip_segment(pr.x0, pr.y0, dx, dy, 0, width, row0, row1 + 1, &ua, &ub)) return;
  auto deposit = [&](double u, double share) {
    const double x = pr.x0 + u * dx, y = pr.y0 + u * dy;
    const int ix = std::clamp(int(std::floor(x)), 0, width - 1);
    const int iy = std::clamp(int(std::floor(y)), row0, row1);
    const double z = pr.z0 + u * (double(pr.z1) - pr.z0);
    if (!(z < depth.at(ix, iy))) return;  // behind the scene
    out->push_back({iy * width + ix, float(mass * share)});
  };
  if (dx == 0 && dy == 0) {
    deposit(0, 1.0);
    return;
  }
  // Parameters where the segment crosses pixel boundaries inside [ua, ub].
  thread_local std::vector<double> cuts;
  cuts.clear();
  cuts.push_back(ua);
  cuts.push_back(ub);
  auto add_crossings = [&](double p0, double d) {
    if (d == 0) return;
    const double a = p0 + ua * d, b = p0 + ub * d;
    for (double c = std::floor(std::min(a, b)) + 1; c < std::max(a, b); c += 1) cuts.push_back((c - p0) / d);
  };
  add_crossings(pr.x0, dx);
  add_crossings(pr.y0, dy);
  std::sort(cuts.begin(), cuts.end());
  for (size_t i = 0; i + 1 < cuts.size(); ++i) {
    const double du = cuts[i + 1] - cuts[i];
    if (du > 0) deposit(0.5 * (cuts[i] + cuts[i + 1]), du);
  }
}

// Disk kernel: exact time fraction inside the moving disk, S x S points per pixel.
void raster_disk(const SplatPrimitive& pr, int width, int height, int row0, int row1, const Image& depth,
                 std::vector<PixelAlpha>* out) {
  const double r = pr.radius_px, r2 = r * r;
  const double dx = double(pr.x1) - pr.x0, dy = double(pr.y1) - pr.y0;
  const double a = dx * dx + dy * dy;
  // Bounding box of the part of the capsule that can touch the image.
  double ua = 0, ub = 1;
  if (!clip_segment(pr.x0, pr.y0, dx, dy, -r, width + r, row0 - r, row1 + 1 + r, &ua, &ub)) return;
  const double ya = pr.y0 + ua * dy, yb = pr.y0 + ub * dy;
  const int py0 = std::max(row0, int(std::floor(std::min(ya, yb) - r)));
  const int py1 = std::min({row1, height - 1, int(std::floor(std::max(ya, yb) + r))});
  // Points per pixel side: the disk's edge is resolved at ~1/24 of its radius (lattice-counting
  // error of the covered area ~2% at R = 1 px, below 1% from R = 2 px).
  const int s = std::clamp(int(std::ceil(24.0 / r)), 1, 8);
  const double scale = double(pr.a0) * pr.weight / (s * s);
  for (int y = py0; y <= py1; ++y) {
    // The part of the segment whose capsule reaches this row: a tight x range for diagonal streaks.
    double u0 = ua, u1 = ub;
    if (dy != 0) {
      const double a0 = (y - r - pr.y0) / dy, a1 = (y + 1 + r - pr.y0) / dy;
      u0 = std::max(ua, std::min(a0, a1));
      u1 = std::min(ub, std::max(a0, a1));
      if (u0 > u1) continue;
    }
    const double xr0 = pr.x0 + u0 * dx, xr1 = pr.x0 + u1 * dx;
    const int px0 = std::max(0, int(std::floor(std::min(xr0, xr1) - r)));
    const int px1 = std::min(width - 1, int(std::floor(std::max(xr0, xr1) + r)));
    for (int x = px0; x <= px1; ++x) {
      const double zd = depth.at(x, y);
      double sum = 0;
      for (int sy = 0; sy < s; ++sy) {
        for (int sx = 0; sx < s; ++sx) {
          const double qx = x + (sx + 0.5) / s, qy = y + (sy + 0.5) / s;
          const double ax = pr.x0 - qx, ay = pr.y0 - qy;
          const double c = ax * ax + ay * ay - r2;
          double u0, u1;
          if (a < 1e-18) {
            if (c >= 0) continue;
            u0 = 0, u1 = 1;
          } else {
            const double b = 2 * (ax * dx + ay * dy);
            const double disc = b * b - 4 * a * c;
            if (disc <= 0) continue;
            const double sq = std::sqrt(disc);
            u0 = std::max(0.0, (-b - sq) / (2 * a));
            u1 = std::min(1.0, (-b + sq) / (2 * a));
            if (u1 <= u0) continue;
          }
          const double um = 0.5 * (u0 + u1);
          const double z = pr.z0 + um * (double(pr.z1) - pr.z0);
          if (z < zd) sum += u1 - u0;
        }
      }
      if (sum > 0) out->push_back({y * width + x, float(sum * scale)});
    }
  }
}
}  // namespace

void RenderOptions::validate(const std::string& where) const {
  auto bad = [&](const std::string& what) { throw InputError(where, what); };
  if (segments < 1 || segments > 256) bad("segments must be in [1, 256], got " + std::to_string(segments));
  if (time_samples < 1 || time_samples > 4096)
    bad("time_samples must be in [1, 4096], got " + std::to_string(time_samples));
  if (!(visibility_cutoff > 0 && visibility_cutoff < 1))
    bad("visibility_cutoff must be in (0, 1), got " + std::to_string(visibility_cutoff));
  if (!(near_m > 0 && near_m < 10)) bad("near_m must be in (0, 10), got " + std::to_string(near_m));
  if (!(max_distance_m > near_m && max_distance_m <= 10000))
    bad("max_distance_m must be in (near_m, 10000], got " + std::to_string(max_distance_m));
}

double visibility_distance_m(double f_px, double r_m, double a0, const RenderOptions& options) {
  const double d = f_px * r_m * std::sqrt(kPi * a0 / options.visibility_cutoff);
  return std::min(d, options.max_distance_m);
}

EnvironmentLight make_environment_light(const Image& img, const Eigen::Vector3f& sky) {
  WGS_CHECK(img.space == ColorSpace::kLinear);
  WGS_CHECK_GE(img.channels, 3);
  const int w = img.width, h = img.height;
  const int radius = std::max(1, std::max(w, h) / 4);
  // Summed-area table in double (OpenCV's integral image): exact enough for any image size here, and
  // single-threaded, so order-fixed.
  cv::Mat rgb(h, w, CV_32FC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) rgb.ptr<float>(y)[x * 3 + c] = img.at(x, y, c);
  cv::Mat sat;
  cv::integral(rgb, sat, CV_64F);
  auto at = [&](int x, int y, int c) { return sat.ptr<double>(y)[x * 3 + c]; };
  EnvironmentLight env;
  env.sky = sky;
  env.wide = Image(w, h, 3, ColorSpace::kLinear);
  for (int y = 0; y < h; ++y) {
    const int y0 = std::max(0, y - radius), y1 = std::min(h, y + radius + 1);
    for (int x = 0; x < w; ++x) {
      const int x0 = std::max(0, x - radius), x1 = std::min(w, x + radius + 1);
      const double n = double(x1 - x0) * (y1 - y0);
      for (int c = 0; c < 3; ++c)
        env.wide.at(x, y, c) = float((at(x1, y1, c) - at(x0, y1, c) - at(x1, y0, c) + at(x0, y0, c)) / n);
    }
  }
  return env;
}

float FogState::transmittance(double ray_length_m) const {
  if (!(beta_per_m > 0)) return 1.0f;
  if (!(ray_length_m > 0)) return 1.0f;
  return float(std::exp(-beta_per_m * ray_length_m));  // exp(-inf) = 0 for the background
}

std::vector<double> path_sample_times(const RenderOptions& o, double t, double exposure) {
  std::vector<double> times;
  if (o.streak == StreakMode::kAnalytic) {
    for (int i = 0; i <= o.segments; ++i) times.push_back(t + exposure * double(i) / o.segments);
  } else {
    for (int i = 0; i < o.time_samples; ++i) times.push_back(t + exposure * (i + 0.5) / o.time_samples);
  }
  return times;
}

void SplatList::append(const SplatList& other) {
  const int offset = int(primitives.size());
  primitives.insert(primitives.end(), other.primitives.begin(), other.primitives.end());
  for (Splat s : other.splats) {
    s.first += offset;
    splats.push_back(s);
  }
}

bool add_splat(const RenderView& view, const RenderOptions& options, const Eigen::Vector3d* p_world,
               int n, double visual_radius_m, double opacity, int source, SplatList* out) {
  const Camera& cam = view.camera;
  const double f = view.f_px();
  const double max_radius = 2.0 * std::max(cam.width, cam.height);
  const bool dots = options.streak == StreakMode::kTimeSamples;
  struct End {
    double x, y, z, radius, mass;
  };
  // Footprint of the particle at camera point p: radius and mass (alpha x pixel area).
  auto end_of = [&](const Eigen::Vector3d& p) {
    const double r_drop = f * visual_radius_m / p.z();
    const double coc = view.lens ? view.lens->coc_radius_px(f, p.z()) : 0.0;
    const double radius = std::min(std::sqrt(r_drop * r_drop + coc * coc), max_radius);
    const Eigen::Vector2d uv = cam.project_camera(p);
    return End{uv.x(), uv.y(), p.z(), radius, opacity * kPi * r_drop * r_drop};
  };
  std::vector<Eigen::Vector3d> pc(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) pc[size_t(i)] = cam.to_camera(p_world[i]);
  const int first = int(out->primitives.size());
  // Visibility, extent and shading are decided on the path's pieces (`pieces`: one per segment or
  // dot); the primitives drawn may subdivide a piece (perspective below), so the set of particles
  // drawn does not depend on the subdivision.
  double length_px = 0, max_a0 = 0, mean_radius = 0, total_weight = 0;
  double bx0 = 1e300, bx1 = -1e300, by0 = 1e300, by1 = -1e300;  // of the pieces: outside the image?
  double dy0 = 1e300, dy1 = -1e300;                             // of the primitives: rows touched
  thread_local std::vector<std::pair<End, End>> pieces;  // no allocation per particle
  pieces.clear();
  auto piece = [&](const End& a, const End& b, double weight) {
    const double radius = 0.5 * (a.radius + b.radius);
    const double mass = 0.5 * (a.mass + b.mass);
    const double a0 = double(float(std::min(opacity, mass / (kPi * radius * radius))));
    length_px += std::hypot(b.x - a.x, b.y - a.y);
    max_a0 = std::max(max_a0, a0 * (radius < 0.5 ? kPi * radius * radius : 1.0));
    mean_radius += radius * weight;
    total_weight += weight;
    bx0 = std::min({bx0, a.x - radius, b.x - radius});
    bx1 = std::max({bx1, a.x + radius, b.x + radius});
    by0 = std::min({by0, a.y - radius, b.y - radius});
    by1 = std::max({by1, a.y + radius, b.y + radius});
    pieces.emplace_back(a, b);
  };
  auto push = [&](const End& a, const End& b, double weight) {
    SplatPrimitive pr;
    const double radius = 0.5 * (a.radius + b.radius);
    const double mass = 0.5 * (a.mass + b.mass);
    pr.x0 = float(a.x), pr.y0 = float(a.y), pr.z0 = float(a.z);
    pr.x1 = float(b.x), pr.y1 = float(b.y), pr.z1 = float(b.z);
    pr.radius_px = float(radius);
    pr.a0 = float(std::min(opacity, mass / (kPi * radius * radius)));
    pr.weight = float(weight);
    out->primitives.push_back(pr);
    dy0 = std::min({dy0, a.y - radius, b.y - radius});
    dy1 = std::max({dy1, a.y + radius, b.y + radius});
  };
  // Primitives per straight piece a-b (camera frame, constant speed): the image position f x / z and
  // the footprint change non-linearly with time as the depth changes, while a primitive moves at
  // constant image speed with a linearly blended footprint. The error at the piece's middle time
  // (position and radius, pixels) falls as 1 / k^2 with k equal-time primitives; k keeps it below
  // kPerspectiveTolerancePx. Far particles keep k = 1; a drop moving in depth near the lens needs
  // several (it spends more of the exposure at its streak's far end, where its footprint is smaller).
  auto perspective_pieces = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const End& ea, const End& eb) {
    const End em = end_of(0.5 * (a + b));
    const double err = std::max(std::hypot(em.x - 0.5 * (ea.x + eb.x), em.y - 0.5 * (ea.y + eb.y)),
                                std::abs(em.radius - 0.5 * (ea.radius + eb.radius)));
    if (!(err > kPerspectiveTolerancePx)) return 1;
    return int(std::min(double(kMaxPerspectivePieces), std::ceil(std::sqrt(err / kPerspectiveTolerancePx))));
  };
  const double near = options.near_m;
  if (dots) {
    for (int i = 0; i < n; ++i) {
      if (!(pc[size_t(i)].z() >= near)) continue;
      const End e = end_of(pc[size_t(i)]);
      piece(e, e, 1.0 / n);
      push(e, e, 1.0 / n);
    }
    // Dots of a moving particle trace the same streak: the span between the first and the last
    // covers (n - 1) / n of it.
    const int k = int(out->primitives.size()) - first;
    if (k >= 2) {
      const SplatPrimitive &p0 = out->primitives[size_t(first)], &p1 = out->primitives.back();
      length_px = std::hypot(p1.x0 - p0.x0, p1.y0 - p0.y0) * n / std::max(1, n - 1);
    }
  } else {
    const int segments = n - 1;
    for (int i = 0; i < segments; ++i) {
      Eigen::Vector3d a = pc[size_t(i)], b = pc[size_t(i) + 1];
      double ua = 0, ub = 1;
      if (a.z() < near && b.z() < near) continue;
      if (a.z() < near) ua = (near - a.z()) / (b.z() - a.z());
      if (b.z() < near) ub = (near - a.z()) / (b.z() - a.z());
      const Eigen::Vector3d a2 = pc[size_t(i)] + ua * (pc[size_t(i) + 1] - pc[size_t(i)]);
      const Eigen::Vector3d b2 = pc[size_t(i)] + ub * (pc[size_t(i) + 1] - pc[size_t(i)]);
      a = a2, b = b2;
      a.z() = std::max(a.z(), near), b.z() = std::max(b.z(), near);  // rounding at the clip
      const End ea = end_of(a), eb = end_of(b);
      const double weight = (ub - ua) / segments;
      piece(ea, eb, weight);
      const int k = perspective_pieces(a, b, ea, eb);
      End prev = ea;
      for (int j = 1; j <= k; ++j) {
        const End next = j == k ? eb : end_of(a + (b - a) * (double(j) / k));
        push(prev, next, weight / k);
        prev = next;
      }
    }
  }
  const int count = int(out->primitives.size()) - first;
  auto reject = [&] {
    out->primitives.resize(size_t(first));
    return false;
  };
  if (count == 0) return reject();
  // Outside the image?
  if (bx1 < 0 || by1 < 0 || bx0 > cam.width || by0 > cam.height) return reject();
  // Peak alpha any pixel can reach: a thin streak puts at most ~1.5 / L of its mass in one pixel,
  // a wide one covers a point for at most 2R / L of the exposure.
  mean_radius /= total_weight;
  const double peak = mean_radius < 0.5
                          ? std::min(1.0, max_a0) * std::min(1.0, 1.5 / std::max(length_px, 1e-9))
                          : max_a0 * std::min(1.0, 2 * mean_radius / std::max(length_px, 1e-9));
  if (peak * total_weight < options.visibility_cutoff) return reject();
  Splat s;
  s.first = first;
  s.count = count;
  s.source = source;
  s.y_min = std::max(0, int(std::floor(std::min(by0, dy0))));
  s.y_max = std::min(cam.height - 1, int(std::floor(std::max(by1, dy1))));
  const std::pair<End, End>& mid = pieces[pieces.size() / 2];
  s.mid_x = 0.5f * (float(mid.first.x) + float(mid.second.x));
  s.mid_y = 0.5f * (float(mid.first.y) + float(mid.second.y));
  s.mid_z = 0.5f * (float(mid.first.z) + float(mid.second.z));
  const Eigen::Vector3d pm = pc[size_t(n / 2)];
  s.mid_ray_m = float(pm.z() > 0 ? pm.norm() : double(s.mid_z));
  out->splats.push_back(s);
  return true;
}

void shade_splats(const EnvironmentLight& env, const ParticleRadianceGrid* optics, const FogState& fog,
                  const ParticleAppearance& ap, SplatList* list) {
  WGS_CHECK(ap.shading == ParticleShading::kWeighted || optics != nullptr || list->splats.empty());
  for (Splat& s : list->splats) {
    const int x = std::clamp(int(std::floor(s.mid_x)), 0, env.wide.width - 1);
    const int y = std::clamp(int(std::floor(s.mid_y)), 0, env.wide.height - 1);
    Eigen::Vector3f l;
    if (ap.shading == ParticleShading::kOptics) {
      l = optics->at(s.mid_x, s.mid_y);
    } else {
      for (int c = 0; c < 3; ++c)
        l[c] = float(ap.environment_weight * env.wide.at(x, y, c) + ap.sky_weight * env.sky[c]);
    }
    const float t = fog.transmittance(s.mid_ray_m);
    s.radiance = l * t + fog.airlight * (1.0f - t);
  }
}

ParticleRaster rasterize_splats(const RenderView& view, const SplatList& list, const RenderOptions& options) {
  const int w = view.camera.width, h = view.camera.height;
  WGS_CHECK(view.depth != nullptr);
  WGS_CHECK(view.depth->width == w && view.depth->height == h && view.depth->channels == 1);
  const int bands = (h + kBandRows - 1) / kBandRows;
  std::vector<std::vector<int>> band_splats(static_cast<size_t>(bands));
  for (size_t i = 0; i < list.splats.size(); ++i) {
    const Splat& s = list.splats[i];
    for (int b = s.y_min / kBandRows; b <= s.y_max / kBandRows && b < bands; ++b) band_splats[size_t(b)].push_back(int(i));
  }
  // Double accumulators: 1 - prod(1 - alpha) of many faint particles keeps its precision.
  std::vector<double> trans(size_t(w) * h, 1.0), sum_a(size_t(w) * h, 0.0), sum_l(size_t(w) * h * 3, 0.0);
  std::unique_ptr<std::atomic<uint8_t>[]> visible(new std::atomic<uint8_t>[list.splats.size()]);
  for (size_t i = 0; i < list.splats.size(); ++i) visible[i] = 0;
  parallel_for(0, bands, [&](int64_t b) {
    const int row0 = int(b) * kBandRows, row1 = std::min(h - 1, row0 + kBandRows - 1);
    std::vector<PixelAlpha> px;
    for (int si : band_splats[size_t(b)]) {
      const Splat& s = list.splats[size_t(si)];
      px.clear();
      for (int k = 0; k < s.count; ++k) {
        const SplatPrimitive& pr = list.primitives[size_t(s.first + k)];
        if (pr.radius_px < 0.5f) raster_point(pr, w, row0, row1, *view.depth, &px);
        else raster_disk(pr, w, h, row0, row1, *view.depth, &px);
      }
      std::stable_sort(px.begin(), px.end(), [](const PixelAlpha& a, const PixelAlpha& c) { return a.pixel < c.pixel; });
      bool vis = false;
      for (size_t i = 0; i < px.size();) {
        const int p = px[i].pixel;
        float alpha = 0;
        for (; i < px.size() && px[i].pixel == p; ++i) alpha += px[i].alpha;
        alpha = std::min(alpha, 1.0f);
        if (!(alpha > 0)) continue;
        trans[size_t(p)] *= 1.0 - double(alpha);
        sum_a[size_t(p)] += alpha;
        for (int c = 0; c < 3; ++c) sum_l[size_t(p) * 3 + c] += alpha * s.radiance[c];
        if (alpha >= options.visibility_cutoff) vis = true;
      }
      if (vis) visible[size_t(si)] = 1;
    }
  });
  ParticleRaster r;
  r.alpha = Image(w, h, 1, ColorSpace::kLinear);
  r.radiance = Image(w, h, 3, ColorSpace::kLinear);
  for (size_t p = 0; p < size_t(w) * h; ++p) {
    r.alpha.data[p] = float(1.0 - trans[p]);
    if (sum_a[p] > 0)
      for (int c = 0; c < 3; ++c) r.radiance.data[p * 3 + c] = float(sum_l[p * 3 + c] / sum_a[p]);
  }
  r.visible.resize(list.splats.size());
  for (size_t i = 0; i < list.splats.size(); ++i) r.visible[i] = visible[i];
  return r;
}

void composite_particles(const ParticleRaster& raster, Image* radiance) {
  WGS_CHECK(raster.alpha.width == radiance->width && raster.alpha.height == radiance->height);
  for (size_t p = 0; p < radiance->num_pixels(); ++p) {
    const float a = raster.alpha.data[p];
    if (!(a > 0)) continue;
    for (int c = 0; c < 3; ++c) {
      float& v = radiance->data[p * radiance->channels + c];
      v = (1.0f - a) * v + a * raster.radiance.data[p * 3 + c];
    }
  }
}

}  // namespace weathergs::generator
