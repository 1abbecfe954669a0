#include "restoration/aef/particle_filter.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace weathergs::restoration::aef {

void ParticleFilterOptions::validate() const {
  if (!(radius_px_at_300 > 0 && radius_px_at_300 <= 64))
    throw InputError("particle filter options", "radius_px_at_300 " + std::to_string(radius_px_at_300) + " must be in (0, 64]");
  if (!(threshold > 0 && threshold < 1))
    throw InputError("particle filter options", "threshold " + std::to_string(threshold) + " must be in (0, 1)");
  if (dilate_px < 0 || dilate_px > 16)
    throw InputError("particle filter options", "dilate_px " + std::to_string(dilate_px) + " must be in [0, 16]");
}

int ParticleFilterOptions::radius_px(int width) const {
  return std::max(1, int(std::lround(radius_px_at_300 * width / 300.0)));
}

ParticleFilterResult filter_particles(const Image& image, const ParticleFilterOptions& o, const std::string& where) {
  o.validate();
  if (image.channels != 3 && image.channels != 4)
    throw InputError(where, "expected an RGB or RGBA image, got " + image.to_string());
  if (image.space != ColorSpace::kSRGB) throw InputError(where, "expected an sRGB image, got " + image.to_string());
  if (image.width < 3 || image.height < 3) throw InputError(where, "image " + image.to_string() + " is too small (3x3 at least)");
  const int w = image.width, h = image.height;
  cv::Mat rgb(h, w, CV_32FC3), lum(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      cv::Vec3f& p = rgb.at<cv::Vec3f>(y, x);
      float s = 0;
      for (int c = 0; c < 3; ++c) {
        const float v = image.at(x, y, c);
        // Non-finite input is bad input, not something to filter.
        if (!std::isfinite(v)) throw InputError(where, "non-finite value at pixel (" + std::to_string(x) + ", " + std::to_string(y) + ")");
        p[c] = v;
        s += v;
      }
      lum.at<float>(y, x) = s / 3.f;
    }
  const int r = o.radius_px(w);
  const cv::Mat disk = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1));
  cv::Mat tophat, mask;
  cv::morphologyEx(lum, tophat, cv::MORPH_TOPHAT, disk, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  cv::compare(tophat, cv::Scalar(o.threshold), mask, cv::CMP_GT);  // 255 where a particle
  if (o.dilate_px > 0) {
    const cv::Mat grow = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * o.dilate_px + 1, 2 * o.dilate_px + 1));
    cv::dilate(mask, mask, grow, cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  }
  cv::Mat opened, fill;
  cv::morphologyEx(rgb, opened, cv::MORPH_OPEN, disk, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  cv::medianBlur(opened, fill, 3);

  ParticleFilterResult out;
  out.restored = Image(w, h, 3, ColorSpace::kSRGB);
  out.mask = Image(w, h, 1, ColorSpace::kLinear);
  size_t masked = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool m = mask.at<uint8_t>(y, x) != 0;
      masked += m;
      out.mask.at(x, y) = m ? 1.f : 0.f;
      const cv::Vec3f& src = m ? fill.at<cv::Vec3f>(y, x) : rgb.at<cv::Vec3f>(y, x);
      for (int c = 0; c < 3; ++c) out.restored.at(x, y, c) = std::clamp(src[c], 0.f, 1.f);
    }
  out.mask_fraction = double(masked) / double(size_t(w) * h);
  return out;
}

}  // namespace weathergs::restoration::aef
