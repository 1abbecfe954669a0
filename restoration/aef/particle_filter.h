// The classical Atmospheric Effect Filter: removes falling particles (snow flakes, rain streaks) from
// one view with grey-scale morphology, no learned weights (docs/restoration.md).
//
// Particles are small, bright structures on the scene: a white top-hat of the luminance (the image
// minus its morphological opening with a disk larger than a particle's half width) isolates them;
// pixels whose top-hat exceeds `threshold` (dilated by `dilate_px`) form the particle mask, and in the
// restored image they take the value of the per-channel opening, smoothed by a 3x3 median. Everything
// else is left exactly as it was. The learned AEF (aef_plugin.h) starts from this filter's decision and
// beats it on the benchmark (docs/restoration.md); this one stays as `weathergs filter --method tophat`.
#pragma once

#include <string>

#include "core/image.h"

namespace weathergs::restoration::aef {

struct ParticleFilterOptions {
  // Disk radius in pixels at a 300 px wide view; scaled with the width (particles are drawn at a fixed
  // angular size), never below 1. Particles up to ~2 radii wide are removed.
  double radius_px_at_300 = 2.0;
  double threshold = 0.05;  // top-hat of the sRGB luminance (mean of R, G, B) above which a pixel is a particle
  int dilate_px = 1;        // grow the mask by this many pixels (a particle's soft rim)

  void validate() const;  // InputError naming the field
  int radius_px(int width) const;
};

struct ParticleFilterResult {
  Image restored;  // sRGB, the input's size, 3 channels
  Image mask;      // 1 channel, 1 = particle, 0 = kept
  double mask_fraction = 0;
};

// `image`: sRGB, 3 or 4 channels (alpha ignored). `where` names the image in errors.
ParticleFilterResult filter_particles(const Image& image, const ParticleFilterOptions& options, const std::string& where);

}  // namespace weathergs::restoration::aef
