// DeSplat-style per-view distractor Gaussians (the `desplat` method; Wang et al., "DeSplat: Decomposed
// Gaussian Splatting for Distractor-Free Rendering", CVPR 2025): every training view owns a few
// Gaussians placed in front of its camera. They are rendered only for their own view, so they can take
// up what that view sees and the others do not (falling particles, drops on the lens, anything the
// multi-view consistent scene cannot explain more cheaply), and they are dropped at test time and
// from the exported model. No pretrained features, as the method is defined here.
//
// Compositing: DeSplat renders the distractors and the scene separately and blends
// C = C_d + (1 - A_d) C_s. We rasterize the scene and the view's distractors in one depth-sorted pass;
// while a pixel's distractors lie in front of its scene Gaussians (they start at a fraction of the
// scene's depth) the two are the same image, and the backward pass is the rasterizer's own (checked
// against finite differences in reconstruction/rasterizer tests). See docs/reconstruction.md.
#pragma once

#include <cstdint>
#include <vector>

#include "core/camera.h"
#include "reconstruction/gaussians.h"

namespace weathergs::reconstruction {

// owner[i] of a Gaussian: kSceneOwner for the scene, else the index of the training view it belongs to.
constexpr int32_t kSceneOwner = -1;

struct DistractorPlacement {
  // Depths uniform in inverse depth between these fractions of the median depth of the scene's
  // Gaussians in front of the camera (the camera's "scene depth"), and never nearer than near_m
  // (the rasterizer culls depth <= 0.2 m).
  double near_fraction = 0.1, far_fraction = 0.5;
  double near_m = 0.3;
  double initial_opacity = 0.01;
};

// Appends `per_view` distractors for each camera to g and their owners to owner (owner must already
// hold one entry per Gaussian of g). Pixel positions are uniform over the image, the scale is
// isotropic and sized so that per_view footprints cover the image once, the colour is mid grey.
// Randomness is keyed on (seed, view, k).
void add_distractors(const std::vector<Camera>& cameras, int per_view, uint64_t seed,
                     const DistractorPlacement& placement, GaussianSet<float>* g, std::vector<int32_t>* owner);

// Rows of the Gaussians rendered for `view`: the scene's and that view's distractors, in order.
void rows_for_view(const std::vector<int32_t>& owner, int view, std::vector<int64_t>* rows);
// sub = the given rows of g, in order.
void gather_rows(const GaussianSet<float>& g, const std::vector<int64_t>& rows, GaussianSet<float>* sub);
// full = n rows of zeros, with row rows[k] = sub's row k (the gradient of Gaussians not rendered is 0).
void scatter_rows(const GaussianSet<float>& sub, const std::vector<int64_t>& rows, size_t n, GaussianSet<float>* full);
// The scene alone (owner == kSceneOwner), in order: what is exported and rendered at test time.
GaussianSet<float> scene_rows(const GaussianSet<float>& g, const std::vector<int32_t>& owner);

}  // namespace weathergs::reconstruction
