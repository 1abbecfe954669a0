#include "generator/lens/lens_render.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/constants.h"
#include "core/thin_lens.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/rng.h"

namespace weathergs::generator::lens {

namespace {

// Blur diameters below one pixel leave the droplet layer as traced.
constexpr double kMinBlurDiameterPx = 1.0;

struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // [x0, x1) x [y0, y1)
  bool empty() const { return x1 <= x0 || y1 <= y0; }
};

// Pixel rectangle (extended raster coordinates) that contains the projection of a ball, or the whole
// raster when the ball reaches behind the image plane.
PixelRect project_ball(const Camera& cam, const Eigen::Vector3d& c, double r, int pad, int ew, int eh) {
  PixelRect all{0, 0, ew, eh};
  if (c.z() + r <= 0) return PixelRect{};
  if (c.z() - r <= 1e-9 * (1 + c.norm())) return all;
  double u0 = 1e300, v0 = 1e300, u1 = -1e300, v1 = -1e300;
  for (int k = 0; k < 8; ++k) {
    Eigen::Vector3d p = c + r * Eigen::Vector3d(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1);
    Eigen::Vector2d uv = cam.project_camera(p);
    u0 = std::min(u0, uv.x());
    v0 = std::min(v0, uv.y());
    u1 = std::max(u1, uv.x());
    v1 = std::max(v1, uv.y());
  }
  auto clampi = [](double v, int lo, int hi) { return int(std::clamp(v, double(lo), double(hi))); };
  return PixelRect{clampi(std::floor(u0) - 1 + pad, 0, ew), clampi(std::floor(v0) - 1 + pad, 0, eh),
                   clampi(std::ceil(u1) + 1 + pad, 0, ew), clampi(std::ceil(v1) + 1 + pad, 0, eh)};
}

// Bilinear lookup at pixel coordinates (u, v) (pixel centers at i + 0.5), edge-clamped.
Eigen::Vector3d sample_bilinear(const Image& img, double u, double v) {
  const double x = std::clamp(u - 0.5, 0.0, double(img.width - 1));
  const double y = std::clamp(v - 0.5, 0.0, double(img.height - 1));
  const int x0 = std::min(int(x), img.width - 1), y0 = std::min(int(y), img.height - 1);
  const int x1 = std::min(x0 + 1, img.width - 1), y1 = std::min(y0 + 1, img.height - 1);
  const double fx = x - x0, fy = y - y0;
  Eigen::Vector3d out;
  for (int c = 0; c < 3; ++c) {
    out[c] = (1 - fy) * ((1 - fx) * img.at(x0, y0, c) + fx * img.at(x1, y0, c)) +
             fy * ((1 - fx) * img.at(x0, y1, c) + fx * img.at(x1, y1, c));
  }
  return out;
}

// Normalized disk kernel of the given diameter, each tap weighted by the area of its pixel inside
// the disk (8x8 supersampling).
cv::Mat disk_kernel(double diameter_px) {
  const double r = diameter_px / 2;
  const int half = int(std::ceil(r - 0.5));
  const int size = 2 * half + 1;
  cv::Mat k(size, size, CV_32F);
  double sum = 0;
  for (int y = 0; y < size; ++y) {
    for (int x = 0; x < size; ++x) {
      int inside = 0;
      for (int sy = 0; sy < 8; ++sy)
        for (int sx = 0; sx < 8; ++sx) {
          const double dx = x - half - 0.5 + (sx + 0.5) / 8, dy = y - half - 0.5 + (sy + 0.5) / 8;
          inside += dx * dx + dy * dy <= r * r;
        }
      k.at<float>(y, x) = float(inside / 64.0);
      sum += inside / 64.0;
    }
  }
  WGS_CHECK_GT(sum, 0.0);
  k /= sum;
  return k;
}

}  // namespace

namespace {

// Disk blur of a layer given at 1/k resolution (diameter in full-resolution pixels), upsampled
// bilinearly by k and cropped to cols x rows.
cv::Mat blur_reduced(const cv::Mat& small, double diameter_px, int k, int cols, int rows) {
  cv::Mat blurred, up;
  cv::filter2D(small, blurred, -1, disk_kernel(diameter_px / k), cv::Point(-1, -1), 0, cv::BORDER_CONSTANT);
  if (k == 1) return blurred;
  cv::resize(blurred, up, cv::Size(small.cols * k, small.rows * k), 0, 0, cv::INTER_LINEAR);
  return up(cv::Rect(0, 0, cols, rows)).clone();
}

// Reduction factor for a blur of this diameter (1: full resolution).
int blur_reduction(double diameter_px, double full_resolution_max_px) {
  if (diameter_px <= full_resolution_max_px) return 1;
  return std::max(2, int(std::floor(diameter_px / full_resolution_max_px)));
}

}  // namespace

cv::Mat disk_blur(const cv::Mat& layer, double diameter_px, double full_resolution_max_px) {
  const int k = blur_reduction(diameter_px, full_resolution_max_px);
  if (k == 1) return blur_reduced(layer, diameter_px, 1, layer.cols, layer.rows);
  // Zero-padded to a multiple of k so that both resamplings are exact integer factors.
  const int w = (layer.cols + k - 1) / k * k, h = (layer.rows + k - 1) / k * k;
  cv::Mat padded(h, w, layer.type(), cv::Scalar::all(0)), small;
  layer.copyTo(padded(cv::Rect(0, 0, layer.cols, layer.rows)));
  cv::resize(padded, small, cv::Size(w / k, h / k), 0, 0, cv::INTER_AREA);
  return blur_reduced(small, diameter_px, k, layer.cols, layer.rows);
}

namespace {

uint64_t pixel_key(int x, int y) {
  // Offsets keep guard-band pixels (negative coordinates) distinct and positive.
  constexpr int64_t kOffset = int64_t(1) << 30;
  return (uint64_t(int64_t(y) + kOffset) << 32) | uint64_t(uint32_t(int64_t(x) + kOffset));
}

}  // namespace

uint64_t fnv1a64(const std::string& s) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

LensDropletRenderer::LensDropletRenderer(const LensDropletSpec& spec, uint64_t seed, const Camera& reference)
    : spec_(spec), seed_(seed) {
  validate_lens_droplet_spec(spec_, "lens_droplets");
  WGS_CHECK(spec_.attach == Attach::kLens || spec_.window.has_value());
  field_ = sample_drop_field(spec_, seed_, reference);
  if (!field_.drops.empty()) device_ = std::make_unique<EmbreeDevice>();
}

LensViewResult LensDropletRenderer::render(const Image& image, const Camera& camera, double time_s, const Eigen::Vector3f* sky) const {
  const std::string where = "view " + camera.name;
  if (image.channels != 3 || image.space != ColorSpace::kLinear)
    throw InputError(where, "lens droplets need a linear RGB image, got " + image.to_string());
  if (image.width != camera.width || image.height != camera.height)
    throw InputError(where, "image " + image.to_string() + " does not match the camera size " +
                                std::to_string(camera.width) + "x" + std::to_string(camera.height));
  require_finite(image, where);
  if (!std::isfinite(time_s)) throw InputError(where, "time_s is not finite");
  const int w = image.width, h = image.height;

  LensViewResult res;
  res.image = image;
  res.coverage = Image(w, h, 1, ColorSpace::kLinear, 0.f);
  res.mask = Image(w, h, 1, ColorSpace::kLinear, 0.f);
  res.drops = Json{{"view", camera.name}, {"time_s", time_s}, {"blur_diameter_px", 0.0},
                   {"drops", Json::array()}};
  if (!device_) return res;

  const GlassPlane plane = place_glass(field_, camera);
  std::vector<PlacedDrop> placed = place_drops(field_, camera, time_s);

  // Defocus of the glass: its distance along the optical axis (or the median drop depth when the
  // axis misses the plane, e.g. a window seen edge-on).
  double blur = 0;
  bool blur_clipped = false;
  if (spec_.defocus && !placed.empty()) {
    double dist = -1;
    const double nz = plane.water_normal.z();
    if (std::abs(nz) > 1e-9) dist = plane.point.dot(plane.water_normal) / nz;
    if (!(dist > 0)) {
      std::vector<double> z;
      for (const PlacedDrop& p : placed) z.push_back(p.base_center.z());
      std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
      dist = z[z.size() / 2];
    }
    const std::optional<ThinLens> lens = thin_lens_of(camera);
    if (lens && dist > 0) blur = lens->coc_diameter_px(camera.fx, dist);
    if (blur > kMaxBlurDiameterPx) {
      blur = kMaxBlurDiameterPx;
      blur_clipped = true;
    }
    if (blur < kMinBlurDiameterPx) blur = 0;
  }
  // Guard band: drops just outside the frame blur into it, so trace a margin of the blur radius.
  const int pad = blur > 0 ? int(std::ceil(blur / 2)) + 1 : 0;
  const int ew = w + 2 * pad, eh = h + 2 * pad;

  // Cull drops that cannot reach the traced raster; mark candidate pixels.
  std::vector<PlacedDrop> visible;
  std::vector<uint8_t> candidate(size_t(ew) * eh, 0);
  for (const PlacedDrop& p : placed) {
    const bool cap_below_half = p.contact_angle_rad <= kPi / 2;
    const Eigen::Vector3d c = cap_below_half ? p.base_center : p.sphere_center;
    const double r = cap_below_half ? p.base_radius : p.sphere_radius;
    PixelRect rect = project_ball(camera, c, r, pad, ew, eh);
    if (rect.empty()) continue;
    visible.push_back(p);
    const double dist = c.norm();
    if (r >= dist * 0.999) {  // the camera is (nearly) inside the ball: every pixel of the rectangle
      for (int y = rect.y0; y < rect.y1; ++y)
        std::fill(candidate.begin() + size_t(y) * ew + rect.x0, candidate.begin() + size_t(y) * ew + rect.x1, 1);
      continue;
    }
    // Pixels whose center ray is within the ball's angular radius plus half a pixel diagonal
    // (< 1 / focal length radians anywhere in the image) of its center direction.
    const double cone = std::min(kPi, std::asin(r / dist) + 1.0 / std::min(camera.fx, camera.fy));
    const double cos_cone = std::cos(cone);
    const Eigen::Vector3d axis = c / dist;
    for (int y = rect.y0; y < rect.y1; ++y) {
      const double dy = (y - pad + 0.5 - camera.cy) / camera.fy;
      uint8_t* row = candidate.data() + size_t(y) * ew;
      for (int x = rect.x0; x < rect.x1; ++x) {
        const double dx = (x - pad + 0.5 - camera.cx) / camera.fx;
        const double dot = (axis.x() * dx + axis.y() * dy + axis.z()) / std::sqrt(dx * dx + dy * dy + 1);
        if (dot >= cos_cone) row[x] = 1;
      }
    }
  }
  res.blur_diameter_px = blur;
  res.drops["blur_diameter_px"] = blur;
  if (blur_clipped) res.drops["blur_clipped_to_px"] = kMaxBlurDiameterPx;
  for (const PlacedDrop& p : visible) {
    Json j{{"id", p.id},
           {"base_center_camera_m", {p.base_center.x(), p.base_center.y(), p.base_center.z()}},
           {"outline_radius_mm", p.outline_radius * 1e3},
           {"base_radius_mm", p.base_radius * 1e3},
           {"sphere_radius_mm", p.sphere_radius * 1e3},
           {"contact_angle_deg", p.contact_angle_rad * 180 / kPi}};
    if (p.base_center.z() > 0) {
      Eigen::Vector2d uv = camera.project_camera(p.base_center);
      j["center_px"] = {uv.x(), uv.y()};
      j["radius_px"] = camera.fx * p.outline_radius / p.base_center.z();
    } else {
      j["center_px"] = nullptr;
      j["radius_px"] = nullptr;
    }
    res.drops["drops"].push_back(j);
  }
  if (visible.empty()) return res;

  DropScene scene(*device_, plane, std::move(visible), spec_.geometry, spec_.cap_segments);

  Eigen::Vector3d environment;
  if (spec_.environment_radiance) {
    environment = {(*spec_.environment_radiance)[0], (*spec_.environment_radiance)[1],
                   (*spec_.environment_radiance)[2]};
  } else if (spec_.environment_sky) {
    WGS_CHECK(sky != nullptr);
    environment = sky->cast<double>();
  } else {
    // Mean radiance of the view, summed row by row in order (deterministic).
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int y = 0; y < h; ++y) {
      Eigen::Vector3d row = Eigen::Vector3d::Zero();
      for (int x = 0; x < w; ++x)
        for (int c = 0; c < 3; ++c) row[c] += image.at(x, y, c);
      sum += row;
    }
    environment = sum / double(image.num_pixels());
  }

  const Eigen::Vector3d camera_radiance =
      spec_.camera_radiance ? Eigen::Vector3d((*spec_.camera_radiance)[0], (*spec_.camera_radiance)[1],
                                              (*spec_.camera_radiance)[2])
                            : environment;

  TraceOptions topt;
  topt.refractive_index = spec_.refractive_index;
  topt.max_bounces = spec_.max_bounces;
  topt.glass_thickness_m = 1e-3 * spec_.glass_thickness_mm;
  topt.glass_refractive_index = spec_.glass_refractive_index;
  const int spp = spec_.samples_per_pixel;
  const int nx = int(std::ceil(std::sqrt(double(spp))));
  const int ny = (spp + nx - 1) / nx;
  const uint64_t stream = kStreamLensPixels ^ fnv1a64(camera.name);

  // Premultiplied droplet radiance (3) and coverage (1) per trace cell. A cell is one pixel of the
  // extended raster, or k x k pixels when the blur is wide enough to be computed at 1/k resolution
  // (disk_blur): samples_per_pixel stratified samples then cover the whole cell, and the blur averages
  // ~(blur / k)^2 cells, so the noise stays below that of the full-resolution case.
  const int k = blur > 0 ? blur_reduction(blur, kDiskBlurFullResolutionMaxPx) : 1;
  const int tw = (ew + k - 1) / k, th = (eh + k - 1) / k;
  res.drops["trace_cell_px"] = k;
  std::vector<uint8_t> cell_candidate(size_t(tw) * th, 0);
  for (int y = 0; y < eh; ++y)
    for (int x = 0; x < ew; ++x)
      if (candidate[size_t(y) * ew + x]) cell_candidate[size_t(y / k) * tw + x / k] = 1;
  cv::Mat layer(th, tw, CV_32FC4, cv::Scalar::all(0));
  std::vector<int64_t> row_rays(th, 0), row_water(th, 0), row_embree(th, 0);
  const auto t0 = std::chrono::steady_clock::now();
  parallel_for(0, th, [&](int64_t ty) {
    cv::Vec4f* out = layer.ptr<cv::Vec4f>(int(ty));
    const uint8_t* cand = cell_candidate.data() + size_t(ty) * tw;
    const int y = int(ty) * k - pad;  // image coordinates of the cell's top-left pixel
    for (int tx = 0; tx < tw; ++tx) {
      if (!cand[tx]) continue;
      const int x = tx * k - pad;
      Rng rng(seed_, stream ^ uint64_t(k - 1), pixel_key(x, y));
      Eigen::Vector3d radiance = Eigen::Vector3d::Zero();
      int covered = 0;
      for (int s = 0; s < spp; ++s) {
        const double jx = rng.uniform_double(), jy = rng.uniform_double();
        const double u = x + k * ((s % nx) + jx) / nx, v = y + k * ((s / nx) + jy) / ny;
        const Eigen::Vector3d d = Eigen::Vector3d((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0).normalized();
        const PathResult path = trace_path(scene, Eigen::Vector3d::Zero(), d, topt);
        row_embree[ty] += path.boundary_queries;
        if (!path.touched_water) continue;
        ++covered;
        Eigen::Vector3d l = path.environment_weight * environment + path.camera_weight * camera_radiance;
        if (path.scene_weight > 0) {
          const Eigen::Vector3d& e = path.exit_direction;
          l += path.scene_weight * sample_bilinear(image, camera.fx * e.x() / e.z() + camera.cx,
                                                   camera.fy * e.y() / e.z() + camera.cy);
        }
        radiance += l;
      }
      row_rays[ty] += spp;
      row_water[ty] += covered;
      out[tx] = cv::Vec4f(float(radiance[0] / spp), float(radiance[1] / spp), float(radiance[2] / spp),
                          float(double(covered) / spp));
    }
  });
  for (int y = 0; y < th; ++y) {
    res.camera_rays += row_rays[y];
    res.water_rays += row_water[y];
    res.embree_rays += row_embree[y];
  }
  const auto t1 = std::chrono::steady_clock::now();
  res.trace_seconds = std::chrono::duration<double>(t1 - t0).count();
  device_->throw_if_error("tracing view " + camera.name);

  if (blur > 0) layer = blur_reduced(layer, blur, k, ew, eh);
  res.blur_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  for (int y = 0; y < h; ++y) {
    const cv::Vec4f* row = layer.ptr<cv::Vec4f>(y + pad) + pad;
    for (int x = 0; x < w; ++x) {
      const float cov = std::clamp(row[x][3], 0.f, 1.f);
      res.coverage.at(x, y) = cov;
      if (spec_.mask_rule == LensMaskRule::kCoverage) res.mask.at(x, y) = cov >= spec_.mask_threshold ? 1.f : 0.f;
      if (cov == 0.f && row[x][0] == 0.f && row[x][1] == 0.f && row[x][2] == 0.f) continue;
      float change_levels = 0;
      for (int c = 0; c < 3; ++c) {
        const float out = std::max(0.f, row[x][c]) + (1.f - cov) * image.at(x, y, c);
        res.image.at(x, y, c) = out;
        // Perceptible change: the difference of the two 8-bit sRGB values this pixel would be written as.
        const float q_out = std::round(255.f * std::clamp(linear_to_srgb(out), 0.f, 1.f));
        const float q_in = std::round(255.f * std::clamp(linear_to_srgb(image.at(x, y, c)), 0.f, 1.f));
        change_levels = std::max(change_levels, std::abs(q_out - q_in));
      }
      if (spec_.mask_rule == LensMaskRule::kPerceptible)
        res.mask.at(x, y) = change_levels > float(spec_.mask_min_change_levels) ? 1.f : 0.f;
    }
  }
  return res;
}

}  // namespace weathergs::generator::lens
