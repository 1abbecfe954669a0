// GS-W-style "in the wild" training for 3DGS without GS-W's pretrained image encoder (the gs-w-lite
// method; docs/reconstruction.md, "In the wild"). GS-W (Zhang et al., ECCV 2024) gives each Gaussian
// appearance features sampled from a ResNet/UNet feature map of the training image and learns a
// per-image visibility map for transient occluders. No pretrained encoder can be had here, so:
//   - appearance: per training view an affine colour transform of the render, c' = A_v c + b_v,
//     starting at the identity; test views use the identity (the scene's own colours);
//   - visibility: per training view a free map M_v = sigmoid(m_v), m_v on a grid of cells of
//     `cell_px` pixels, bilinearly upsampled; the loss is the photometric loss of M * render against
//     M * target plus visibility_weight * mean((1 - M)^2) (GS-W's regulariser), the map switched on
//     after `from` iterations (GS-W's warm-up; M = 1 before).
// The map is learned from the L1 term and the regulariser: the D-SSIM term's dependence on M is not
// differentiated (the Gaussians see the full loss). Each view's parameters take an Adam step at the
// iterations that view is trained on. Everything is sequential per view: deterministic.
#pragma once

#include <cstdint>
#include <vector>

#include "core/train_views.h"

namespace weathergs::reconstruction {

struct InTheWildOptions {
  int from = 200;                  // iterations before the visibility map is used
  double visibility_weight = 0.2;  // GS-W-style (1 - M)^2 regulariser
  double lambda_dssim = 0.2;       // the photometric loss's, for the L1 share of the map's gradient
  int cell_px = 8;                 // visibility map resolution
  double appearance_lr = 1e-3, visibility_lr = 0.05;  // Adam (0.9, 0.999)
};

class InTheWild {
 public:
  InTheWild() = default;
  InTheWild(const std::vector<TrainView>& views, const InTheWildOptions& options);
  bool empty() const { return views_.empty(); }

  // The images the loss compares: M * (A c + b) and M * target (H x W x 3).
  void forward(int view, int iteration, const std::vector<float>& render, const std::vector<float>& target,
               std::vector<float>* render_out, std::vector<float>* target_out);
  // v: d loss / d render_out on input, d loss / d render on output. Computes the view's parameter
  // gradients (with the regulariser; affine_grad(), logits_grad()), then step() takes its Adam step.
  void backward(int view, int iteration, const std::vector<float>& render, const std::vector<float>& target,
                std::vector<float>* v);
  void step(int view, int iteration);
  void backward_and_step(int view, int iteration, const std::vector<float>& render, const std::vector<float>& target,
                         std::vector<float>* v) {
    backward(view, iteration, render, target, v);
    step(view, iteration);
  }
  const std::vector<float>& affine_grad() const { return grad_affine_; }
  const std::vector<float>& logits_grad() const { return grad_logits_; }
  // The regulariser visibility_weight * mean((1 - M)^2) of the view at `iteration` (0 before `from`).
  double regulariser(int view, int iteration) const;
  // Parameters, for tests: affine (3x3 row-major then b) and the map's logits (gh x gw).
  std::vector<float>& affine(int view) { return views_[size_t(view)].affine; }
  std::vector<float>& logits(int view) { return views_[size_t(view)].logits; }

  // The view's current visibility (H x W, in (0, 1]) and affine transform (row-major 3x3, then b).
  std::vector<float> visibility(int view) const;
  const std::vector<float>& appearance(int view) const { return views_[size_t(view)].affine; }

  // Checkpoint state: every float (parameters and Adam moments) in a fixed order, and its inverse.
  std::vector<float> state() const;
  void restore(const std::vector<float>& state);  // InputError when the size does not match
  size_t state_size() const;

 private:
  struct View {
    int width = 0, height = 0, gw = 0, gh = 0;
    std::vector<float> affine, affine_m, affine_v, logits, logits_m, logits_v;
    int64_t steps = 0, mask_steps = 0;  // Adam steps of the affine transform and of the map
  };
  void upsample(const View& v, std::vector<float>* m) const;  // sigmoid of the bilinear logits
  InTheWildOptions options_;
  std::vector<View> views_;
  std::vector<float> mask_, grad_affine_, grad_logits_;  // scratch and the last backward's gradients
};

}  // namespace weathergs::reconstruction
