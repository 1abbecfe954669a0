#include "capture/sift_keypoints.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace weathergs::capture {

namespace {

constexpr int kGroups = kSiftNumOctaves * kSiftLevels;  // one per (octave, level), in detection order
// VLFeat: sigma0 = 1.6 * 2^(1/levels); a refined level is at least s_min (-1) and within 1.5 of its
// detection level (0..levels-1), which is also VLFeat's bound on the refined row and column offsets.
const double kSigma0 = 1.6 * std::pow(2.0, 1.0 / kSiftLevels);
constexpr double kLevelMin = -1.0, kMaxOffset = 1.5;
// VLFeat's refinement moves a keypoint at most one pixel per step for five steps and keeps an offset
// below 1.5, so a keypoint lies within 6.5 octave pixels of the row it was found on, and two of one
// scan are out of row order by less than 13; 16 leaves room, far below a new scan's jump to the top.
constexpr double kRowFallback = 16.0;
// Keypoints are stored in float32: a boundary case counts as possible.
constexpr double kSlack = 1e-3;

int octave_of(int group) { return kSiftFirstOctave + group / kSiftLevels; }

// A keypoint's level counted from octave 0's first level (octave o's level l is kSiftLevels * o + l).
double absolute_level(double scale) { return kSiftLevels * std::log2(scale / kSigma0); }

// The group's detection level as an absolute level.
double group_level(int group) { return kSiftLevels * octave_of(group) + group % kSiftLevels; }

// Whether a keypoint of this absolute level can belong to the group's detection level.
bool fits(double level, int group) {
  return std::abs(level - group_level(group)) <= kMaxOffset + kSlack &&
         level - kSiftLevels * octave_of(group) >= kLevelMin - kSlack;
}

}  // namespace

double sift_keypoint_scale(const float* k, int cols) {
  return cols == 4 ? double(k[2]) : std::hypot(double(k[2]), double(k[4]));
}

std::vector<int> sift_keypoint_octaves(const float* keypoints, int rows, int cols) {
  if (rows <= 0) return {};
  constexpr double kNone = std::numeric_limits<double>::infinity();
  // cost[g]: the least total distance to the groups' levels over the keypoints so far, the last in g.
  std::vector<double> cost(kGroups, kNone), next(kGroups);
  std::vector<int8_t> from(size_t(rows) * kGroups, -1);  // the previous keypoint's group
  double previous_row = 0;
  for (int i = 0; i < rows; ++i) {
    const float* k = keypoints + size_t(i) * size_t(cols);
    const double level = absolute_level(sift_keypoint_scale(k, cols)), row = k[1];
    double best_before = kNone;  // min over groups below g of cost, and where
    int best_before_group = -1;
    for (int g = 0; g < kGroups; ++g) {
      next[size_t(g)] = kNone;
      if (fits(level, g)) {
        double c = i == 0 ? 0.0 : kNone;
        int f = -1;
        // The same scan goes on only if the row did not fall back further than refinement allows.
        const double fallback = kRowFallback * std::ldexp(1.0, octave_of(g));
        if (i > 0 && row >= previous_row - fallback - kSlack) c = cost[size_t(g)], f = g;
        if (best_before < c) c = best_before, f = best_before_group;
        if (c < kNone) {
          next[size_t(g)] = c + std::abs(level - group_level(g));
          from[size_t(i) * kGroups + size_t(g)] = int8_t(f);
        }
      }
      if (i > 0 && cost[size_t(g)] < best_before) best_before = cost[size_t(g)], best_before_group = g;
    }
    cost.swap(next);
    previous_row = row;
  }
  int g = -1;
  for (int h = 0; h < kGroups; ++h)
    if (cost[size_t(h)] < kNone && (g < 0 || cost[size_t(h)] < cost[size_t(g)])) g = h;
  if (g < 0) return {};
  std::vector<int> octaves(static_cast<size_t>(rows));
  for (int i = rows - 1; i >= 0; --i) {
    octaves[size_t(i)] = octave_of(g);
    g = from[size_t(i) * kGroups + size_t(g)];
  }
  return octaves;
}

bool sift_descriptor_unwritten(double x, double y, int octave, int width, int height) {
  // VLFeat's octave size (VL_SHIFT_LEFT) and its descriptor's bounds check: (int)(c + 0.5) >= w for
  // x, >= h - 1 for y, in the octave's pixels, where VLFeat's pixel centres are COLMAP's minus 0.5.
  const double per = std::ldexp(1.0, octave);
  const int w = octave < 0 ? width << -octave : width >> octave, h = octave < 0 ? height << -octave : height >> octave;
  const double xo = (x - 0.5) / per, yo = (y - 0.5) / per;
  return !(xo + 0.5 < w - kSlack && yo + 0.5 < h - 1 - kSlack);
}

std::vector<bool> sift_descriptors_unwritten(const float* keypoints, int rows, int cols, int width, int height) {
  std::vector<bool> unwritten(size_t(std::max(rows, 0)), false);
  const std::vector<int> octaves = sift_keypoint_octaves(keypoints, rows, cols);
  for (int i = 0; i < rows; ++i) {
    const float* k = keypoints + size_t(i) * size_t(cols);
    if (!octaves.empty()) {
      unwritten[size_t(i)] = sift_descriptor_unwritten(k[0], k[1], octaves[size_t(i)], width, height);
      continue;
    }
    const double level = absolute_level(sift_keypoint_scale(k, cols));
    bool any = false, all = true;
    for (int g = 0; g < kGroups; g += kSiftLevels) {
      const int o = octave_of(g);
      bool possible = false;
      for (int l = 0; l < kSiftLevels; ++l) possible = possible || fits(level, g + l);
      if (!possible) continue;
      any = true;
      all = all && sift_descriptor_unwritten(k[0], k[1], o, width, height);
    }
    unwritten[size_t(i)] = any && all;
  }
  return unwritten;
}

}  // namespace weathergs::capture
