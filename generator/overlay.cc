#include "generator/overlay.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/constants.h"
#include "core/error.h"
#include "core/json_fields.h"
#include "core/rng.h"
#include "generator/stages.h"

namespace weathergs::generator {

namespace {

constexpr uint64_t kStreamOverlay = 0x4f56524c00000000ull;  // "OVRL"
constexpr double kReferenceWidthPx = 600;                   // sizes are given for this image width
constexpr double kMaxElements = 2e6;                        // per view: far beyond any sensible layer

uint64_t name_hash(const std::string& s) {
  uint64_t h = 1469598103934665603ull;  // FNV-1a
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

// Soft coverage of a pixel at distance d from a shape of half-width r: a one-pixel ramp.
inline float ramp(double r, double d) { return float(std::clamp(r + 0.5 - d, 0.0, 1.0)); }

// Multiplies the transmittance of the pixels under a streak from a to b by (1 - alpha), tapered
// towards the ends (a streak is a drop's motion-blurred path: brightest in the middle).
void draw_streak(cv::Mat& trans, double ax, double ay, double bx, double by, double half_width, double alpha) {
  const int x0 = std::max(0, int(std::floor(std::min(ax, bx) - half_width - 1)));
  const int x1 = std::min(trans.cols - 1, int(std::ceil(std::max(ax, bx) + half_width + 1)));
  const int y0 = std::max(0, int(std::floor(std::min(ay, by) - half_width - 1)));
  const int y1 = std::min(trans.rows - 1, int(std::ceil(std::max(ay, by) + half_width + 1)));
  const double dx = bx - ax, dy = by - ay, len2 = std::max(dx * dx + dy * dy, 1e-12);
  for (int y = y0; y <= y1; ++y) {
    float* row = trans.ptr<float>(y);
    for (int x = x0; x <= x1; ++x) {
      const double px = x + 0.5 - ax, py = y + 0.5 - ay;
      const double t = std::clamp((px * dx + py * dy) / len2, 0.0, 1.0);
      const double d = std::hypot(px - t * dx, py - t * dy);
      const float c = ramp(half_width, d);
      if (c <= 0) continue;
      const double taper = 0.4 + 0.6 * std::sin(kPi * t);
      row[x] *= float(1.0 - alpha * taper * c);
    }
  }
}

void draw_flake(cv::Mat& trans, double cx, double cy, double radius, double alpha) {
  const int x0 = std::max(0, int(std::floor(cx - radius - 1))), x1 = std::min(trans.cols - 1, int(std::ceil(cx + radius + 1)));
  const int y0 = std::max(0, int(std::floor(cy - radius - 1))), y1 = std::min(trans.rows - 1, int(std::ceil(cy + radius + 1)));
  for (int y = y0; y <= y1; ++y) {
    float* row = trans.ptr<float>(y);
    for (int x = x0; x <= x1; ++x) {
      const float c = ramp(radius, std::hypot(x + 0.5 - cx, y + 0.5 - cy));
      if (c > 0) row[x] *= float(1.0 - alpha * c);
    }
  }
}

}  // namespace

OverlayOptions OverlayOptions::defaults(Species species) {
  OverlayOptions o;
  o.species = species;
  if (species == Species::kRain) {
    o.count_per_mpx = 10000;
    o.width_px = 1.5;
    o.opacity = {0.3, 0.7};
    o.brightness = 1.4;
    o.blur_sigma_px = 0.6;
  } else {
    o.count_per_mpx = 4000;
    o.opacity = {0.5, 0.95};
    o.brightness = 1.3;
    o.blur_sigma_px = 0.8;
  }
  return o;
}

void OverlayOptions::validate(const std::string& where) const {
  auto bad = [&](const std::string& what) { throw InputError(where, what); };
  if (!(count_per_mpx >= 0 && count_per_mpx <= 1e6)) bad("count_per_mpx must be in [0, 1e6]");
  if (!(rate_scale >= 0 && std::isfinite(rate_scale))) bad("the rate scale must be finite and >= 0");
  if (!(length_px[0] > 0 && length_px[1] <= 2000)) bad("length_px must be within (0, 2000]");
  if (!(width_px > 0 && width_px <= 50)) bad("width_px must be in (0, 50]");
  if (!(std::abs(angle_deg) <= 80)) bad("angle_deg must be in [-80, 80]");
  if (!(angle_jitter_deg >= 0 && angle_jitter_deg <= 45)) bad("angle_jitter_deg must be in [0, 45]");
  if (!(radius_px[0] > 0 && radius_px[1] <= 200)) bad("radius_px must be within (0, 200]");
  if (!(opacity[0] >= 0 && opacity[1] <= 1)) bad("opacity must be within [0, 1]");
  if (!(brightness >= 0 && brightness <= 100)) bad("brightness must be in [0, 100]");
  if (!(blur_sigma_px >= 0 && blur_sigma_px <= 20)) bad("blur_sigma_px must be in [0, 20]");
}

namespace {
// A missing key keeps the species' default; rain and snow have keys of their own.
constexpr auto kOverlayFields = [](auto& s, auto& f) {
  using json_fields::Bounds;
  f("count_per_mpx", s.count_per_mpx, Bounds{0, 1e6});
  if (s.species == Species::kRain) {
    f("length_px", s.length_px, json_fields::Range{}, Bounds{1e-3, 2000});
    f("width_px", s.width_px, Bounds{1e-3, 50});
    f("angle_deg", s.angle_deg, Bounds{-80, 80});
    f("angle_jitter_deg", s.angle_jitter_deg, Bounds{0, 45});
  } else {
    f("radius_px", s.radius_px, json_fields::Range{}, Bounds{1e-3, 200});
  }
  f("opacity", s.opacity, json_fields::Range{}, Bounds{0, 1});
  f("brightness", s.brightness, Bounds{0, 100});
  f("blur_sigma_px", s.blur_sigma_px, Bounds{0, 20});
};
}  // namespace

OverlayOptions OverlayOptions::from_json(const JsonReader& r, OverlayOptions o) {
  if (!r.is_object()) throw InputError(r.where(), "expected an object (the paper style's 2D overlay)");
  o = json_fields::read(r, o, kOverlayFields, json_fields::Absent::kKeep);
  o.validate(r.where());
  return o;
}

Json OverlayOptions::to_json() const { return json_fields::write(*this, kOverlayFields); }

Image render_overlay_alpha(const OverlayOptions& o, uint64_t seed, const std::string& view_name, int width, int height) {
  WGS_CHECK(width > 0 && height > 0);
  const double scale = width / kReferenceWidthPx;
  const double expected = o.count_per_mpx * o.rate_scale * double(width) * height * 1e-6;
  if (expected > kMaxElements)
    throw InputError("view '" + view_name + "'", "the overlay would draw " + std::to_string(int64_t(expected)) +
                                                     " elements; lower count_per_mpx");
  // Rounded, not Poisson: the layer's density is a style knob, not a physical process.
  const int64_t count = std::llround(expected);
  cv::Mat trans(height, width, CV_32F, cv::Scalar(1.0f));
  Rng rng(seed, kStreamOverlay + uint64_t(o.species), name_hash(view_name));
  const double margin = (o.species == Species::kRain ? o.length_px[1] : o.radius_px[1]) * scale;
  for (int64_t i = 0; i < count; ++i) {
    double u[5];
    for (double& x : u) x = rng.uniform_double();  // a fixed number of draws per element
    const double cx = -margin + u[0] * (width + 2 * margin), cy = -margin + u[1] * (height + 2 * margin);
    const double alpha = o.opacity[0] + (o.opacity[1] - o.opacity[0]) * u[2];
    if (o.species == Species::kRain) {
      const double len = scale * (o.length_px[0] + (o.length_px[1] - o.length_px[0]) * u[3]);
      const double ang = (o.angle_deg + o.angle_jitter_deg * (2 * u[4] - 1)) * kPi / 180;
      const double hx = 0.5 * len * std::sin(ang), hy = 0.5 * len * std::cos(ang);
      draw_streak(trans, cx - hx, cy - hy, cx + hx, cy + hy, 0.5 * o.width_px * scale, alpha);
    } else {
      const double r = scale * o.radius_px[0] * std::pow(o.radius_px[1] / o.radius_px[0], u[3]);
      draw_flake(trans, cx, cy, r, alpha);
    }
  }
  cv::Mat a = 1.0f - trans;
  if (o.blur_sigma_px * scale > 0.05)
    cv::GaussianBlur(a, a, cv::Size(0, 0), o.blur_sigma_px * scale, 0, cv::BORDER_REFLECT);
  Image out(width, height, 1, ColorSpace::kLinear);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) out.at(x, y) = std::clamp(a.at<float>(y, x), 0.0f, 1.0f);
  return out;
}

void OverlayStage::run(WeatherView& v) const {
  const Image a = render_overlay_alpha(options_, seed_, v.camera.name, v.camera.width, v.camera.height);
  const Eigen::Vector3f light = float(options_.brightness) * v.environment.sky;
  for (int y = 0; y < v.camera.height; ++y)
    for (int x = 0; x < v.camera.width; ++x) {
      const float alpha = a.at(x, y);
      if (alpha <= 0) continue;
      for (int c = 0; c < 3; ++c) {
        float& r = v.radiance.at(x, y, c);
        r = (1.0f - alpha) * r + alpha * light[c];
      }
      float& pa = v.particle_alpha.at(x, y);
      pa = 1.0f - (1.0f - pa) * (1.0f - alpha);
    }
  v.has_particles = true;
  v.layers[name() + "_alpha"] = a;
  v.counters[name() + ".elements"] +=
      std::llround(options_.count_per_mpx * options_.rate_scale * double(v.camera.width) * v.camera.height * 1e-6);
}

}  // namespace weathergs::generator
