#include "reconstruction/resolution.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace weathergs::reconstruction {

bool is_downsample_factor(int factor) {
  return factor == 1 || factor == 2 || factor == 4 || factor == 8 || factor == 16;
}

int downsample_factor(int start, double full_at, int iterations, int iteration) {
  WGS_CHECK(is_downsample_factor(start) && full_at > 0 && full_at <= 1 && iterations > 0);
  if (start == 1) return 1;
  const int64_t full = std::max<int64_t>(1, std::llround(full_at * iterations));
  if (iteration >= full) return 1;
  int levels = 0;
  while ((1 << levels) < start) ++levels;
  // Iterations [0, full) in `levels` equal steps; integer arithmetic keeps the boundaries exact.
  const int64_t step = int64_t(std::max(iteration, 0)) * levels / full;
  return start >> step;
}

Camera downsample_camera(const Camera& camera, int factor) {
  WGS_CHECK(is_downsample_factor(factor));
  Camera c = camera;
  if (factor == 1) return c;
  c.width = camera.width / factor;
  c.height = camera.height / factor;
  WGS_CHECK(c.width > 0 && c.height > 0);
  c.fx /= factor;
  c.fy /= factor;
  c.cx /= factor;
  c.cy /= factor;
  return c;
}

TrainView downsample_view(const TrainView& view, int factor) {
  if (factor == 1) return view;
  TrainView out;
  out.camera = downsample_camera(view.camera, factor);
  const int w = out.camera.width, h = out.camera.height, src_w = view.camera.width;
  out.rgb.assign(size_t(w) * h * 3, 0.f);
  if (!view.invalid.empty()) out.invalid.assign(size_t(w) * h, 0);
  const float inv = 1.f / float(factor * factor);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float sum[3] = {0, 0, 0};
      uint8_t masked = 0;
      for (int dy = 0; dy < factor; ++dy)
        for (int dx = 0; dx < factor; ++dx) {
          const size_t p = size_t(y * factor + dy) * src_w + size_t(x * factor + dx);
          for (int c = 0; c < 3; ++c) sum[c] += view.rgb[p * 3 + c];
          if (!view.invalid.empty()) masked |= view.invalid[p] != 0;
        }
      const size_t q = size_t(y) * w + x;
      for (int c = 0; c < 3; ++c) out.rgb[q * 3 + c] = sum[c] * inv;
      if (!out.invalid.empty()) out.invalid[q] = masked;
    }
  return out;
}

}  // namespace weathergs::reconstruction
