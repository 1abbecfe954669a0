// Resolution scheduling (DashGaussian, Chen et al., CVPR 2025, in its plain form): the first part of a
// run trains on box-downsampled images, whose render and loss cost a fraction of the full image's,
// and the factor halves at equal steps until training reaches full resolution. The gradients the
// densification reads are in NDC, which does not change with the image size to first order, so the
// densification threshold holds at every factor.
#pragma once

#include <vector>

#include "core/camera.h"
#include "core/train_views.h"

namespace weathergs::reconstruction {

// True for 1, 2, 4, 8 and 16: the factors a schedule may start from.
bool is_downsample_factor(int factor);

// The factor at a (1-based) iteration of a run of `iterations`: `start` (a power of two) halves
// log2(start) times at equal steps over the first `full_at` (in (0, 1]) of the run, and is 1 from
// iteration round(full_at * iterations) on, so every run ends at full resolution.
int downsample_factor(int start, double full_at, int iterations, int iteration);

// The camera of an image box-downsampled by `factor`: floor(W / f) x floor(H / f) pixels, each the
// mean of an f x f block (a last partial row or column is dropped). With pixel centres at
// (i + 0.5, j + 0.5) (core/camera.h), the intrinsics divide by f exactly.
Camera downsample_camera(const Camera& camera, int factor);

// The view box-downsampled by `factor`: each pixel the mean of its block; a pixel is masked when any
// pixel of its block is, so a masked drop or flake never leaks into the loss. Factor 1 is a copy.
TrainView downsample_view(const TrainView& view, int factor);

}  // namespace weathergs::reconstruction
