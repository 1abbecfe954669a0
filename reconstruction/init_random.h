// Initial Gaussians for a dataset without SfM points (no sparse/0).
//
// kFrustum: uniform over the train views' frusta between near and far, uniform in
// inverse depth, random colours. On a forward-facing rig half of those points start within ~1 m of
// the cameras, where no other view sees them, and training keeps them as floaters (docs/reconstruction.md:
// 13 dB on a street scene that reaches 31 dB from COLMAP points).
//
// kPhotoConsistent (default): the same random rays, but each point is placed at the depth where the
// neighbouring train views agree with the ray's pixel: a plane sweep of one pixel. Per sample: a train
// view A and a pixel uv (both uniform), S depths stratified in inverse depth over [near, far]; at each
// depth the point is projected into A's K nearest train views (by camera centre) and a 5-pixel cross
// (the pixel and its neighbours at +-2 px, on a fronto-parallel patch) is compared in colour; the depth
// with the least mean squared difference, over views that see it, wins, and the point takes the mean
// colour of A and those views. A ray that no neighbour sees at any depth keeps a random stratum and
// A's colour. Masked-out pixels (TrainView::invalid) are never sampled or compared. Every sample is
// keyed on (seed, sample index): the cloud is independent of the thread count.
#pragma once

#include <cstdint>
#include <vector>

#include "reconstruction/gaussians.h"
#include "reconstruction/trainer.h"

namespace weathergs::reconstruction {

constexpr int kPlaneSweepDepths = 48;  // S: depths per ray, stratified in inverse depth
constexpr int kPlaneSweepNeighbors = 4;  // K: nearest train views compared

// Points and colours (sRGB in [0, 1]) of the initialization from options.random_init,
// random_init_count, random_init_near_m/far_m and seed; `views` are the train views (cameras,
// images, masks; kFrustum needs only the cameras).
void sample_random_points(const std::vector<TrainView>& views, const TrainOptions& options,
                          std::vector<Eigen::Vector3d>* points, std::vector<Eigen::Vector3d>* colors);

// Gaussians at those points (init_from_points).
GaussianSet<float> init_random(const std::vector<TrainView>& views, const TrainOptions& options);

}  // namespace weathergs::reconstruction
