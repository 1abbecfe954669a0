// Which of COLMAP 3.8's CPU SIFT descriptors were never written. VLFeat's descriptor step refuses a
// keypoint whose rounded row is its octave's last row, which its detector and orientation step
// accept; COLMAP then stores whatever its buffer held, bytes that differ between runs
// (docs/determinism.md). Whether a keypoint is refused depends on the octave it was detected in,
// which COLMAP does not store but which the order of its keypoints gives.
#pragma once

#include <vector>

namespace weathergs::capture {

// COLMAP 3.8's SIFT extraction: octaves -1 (upsampled) to 2, 3 levels each.
constexpr int kSiftFirstOctave = -1, kSiftNumOctaves = 4, kSiftLevels = 3;

// The scale of a stored keypoint: COLMAP stores (x, y, scale, orientation) or (x, y, a11, a12, a21,
// a22) with affine columns of length `scale`.
double sift_keypoint_scale(const float* keypoint, int cols);

// The octave each keypoint of one image was detected in, from COLMAP's stored order (`rows` x `cols`
// floats, COLMAP's coordinates). VLFeat detects octave by octave and, within one, level by level,
// each level scanned row by row; COLMAP keeps that order. So the keypoints fall into runs, one per
// (octave, level), in increasing order: within a run a keypoint's refined level is within 1.5 of the
// run's and its row never falls back by more than the refinement can move it, while the next run
// starts again from the top. Of the assignments that fit, the one nearest to every keypoint's own
// level is taken. Empty when none fits (keypoints not in the CPU extraction's order).
std::vector<int> sift_keypoint_octaves(const float* keypoints, int rows, int cols);

// Whether VLFeat's descriptor step refuses a keypoint detected in `octave` (COLMAP's coordinates:
// pixel centres at +0.5, on a width x height image): its rounded row is the octave's last, or its
// rounded column past the octave's width.
bool sift_descriptor_unwritten(double x, double y, int octave, int width, int height);

// For each keypoint (`rows` x `cols` floats) whether its stored descriptor is unwritten: at its
// octave from the order above; when the order fits no extraction, when every octave its scale
// allows would refuse it.
std::vector<bool> sift_descriptors_unwritten(const float* keypoints, int rows, int cols, int width, int height);

}  // namespace weathergs::capture
