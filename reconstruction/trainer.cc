#include "reconstruction/trainer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numeric>
#include <sstream>

#include "core/error.h"
#include "core/parallel.h"
#include "core/rng.h"
#include "reconstruction/adam.h"
#include "reconstruction/distractors.h"
#include "reconstruction/resolution.h"

namespace weathergs::reconstruction {

namespace {

constexpr int64_t kChunk = 4096;
// Rng streams of the trainer (the seed is the user's; streams separate the uses).
constexpr uint64_t kStreamViews = 0x7669657773ull;     // epoch permutations
constexpr uint64_t kStreamSplit = 0x73706c6974ull;     // split samples, combined with the iteration

template <typename F>
void for_each_array(GaussianSet<float>& g, F f) {
  f(g.position, ParamGroup::kPosition, 3);
  f(g.log_scale, ParamGroup::kScale, 3);
  f(g.rotation, ParamGroup::kRotation, 4);
  f(g.opacity_logit, ParamGroup::kOpacity, 1);
  f(g.sh, ParamGroup::kShDc, kShFloats);  // DC and rest share the array; see group_of()
}

ParamGroup group_of(ParamGroup array_group, int64_t index) {
  if (array_group != ParamGroup::kShDc) return array_group;
  return index % kShFloats < 3 ? ParamGroup::kShDc : ParamGroup::kShRest;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Scene helpers

Eigen::Vector3d rig_center(const std::vector<Camera>& cameras) {
  WGS_CHECK(!cameras.empty());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Camera& c : cameras) mean += c.center_world();
  return mean / double(cameras.size());
}

double scene_extent(const std::vector<Camera>& cameras) {
  const Eigen::Vector3d mean = rig_center(cameras);
  double max_dist = 0;
  for (const Camera& c : cameras) max_dist = std::max(max_dist, (c.center_world() - mean).norm());
  // One camera (or coincident ones) has no spread: fall back to 1 m so learning rates stay sane.
  return max_dist > 0 ? max_dist * 1.1 : 1.0;
}


// ---------------------------------------------------------------------------------------------
// Trainer

Trainer::Trainer(std::vector<TrainView> views, GaussianSet<float> initial, const TrainOptions& options, double extent)
    : views_(std::move(views)), extent_(extent), g_(std::move(initial)) {
  options.validate("train options");
  WGS_CHECK(!views_.empty());
  std::vector<Camera> cameras;
  for (const TrainView& v : views_) cameras.push_back(v.camera);
  requested_ = options.with_run_length(cameras);
  options_ = requested_.effective();
  WGS_CHECK(extent_ > 0);
  for (const TrainView& v : views_) {
    WGS_CHECK_EQ(v.rgb.size(), size_t(v.camera.width) * v.camera.height * 3);
    if (!v.invalid.empty()) WGS_CHECK_EQ(v.invalid.size(), size_t(v.camera.width) * v.camera.height);
  }
  rig_center_ = rig_center(cameras);
  for (int f = 2; f <= options_.downsample_start; f *= 2) {
    std::vector<TrainView>& level = lowres_.emplace_back();
    for (const TrainView& v : views_) level.push_back(downsample_view(v, f));
  }
  owner_.assign(g_.size(), kSceneOwner);
  if (options_.distractors_per_view > 0) {
    add_distractors(cameras, options_.distractors_per_view, options_.seed, DistractorPlacement{}, &g_, &owner_);
    num_distractors_ = int64_t(cameras.size()) * options_.distractors_per_view;
  }
  if (options_.in_the_wild) {
    InTheWildOptions w;
    w.from = options_.in_the_wild_from;
    w.visibility_weight = options_.visibility_weight;
    w.lambda_dssim = options_.lambda_dssim;
    wild_ = InTheWild(views_, w);
  }
  adam_m_.assign_zero(g_.size());
  adam_v_.assign_zero(g_.size());
  grad_accum_.assign(g_.size(), 0.f);
  grad_count_.assign(g_.size(), 0);
  max_radii_.assign(g_.size(), 0.f);
}

int Trainer::view_for_iteration(int iteration) const {
  const int n = int(views_.size());
  const int epoch = (iteration - 1) / n, pos = (iteration - 1) % n;
  std::vector<int> perm(n);
  std::iota(perm.begin(), perm.end(), 0);
  Rng rng(options_.seed, kStreamViews, uint64_t(epoch));
  for (int i = n - 1; i > 0; --i) std::swap(perm[i], perm[rng.uniform_int(uint32_t(i + 1))]);
  return perm[pos];
}

double Trainer::position_lr(int iteration) const {
  // get_expon_lr_func with no delay: log-linear from init to final over the run, or over what is
  // left of it after position_lr_hold_until (0 gives the reference's expression exactly).
  const int hold = options_.position_lr_hold_until;
  const double t = hold >= options_.iterations
                       ? 0.0
                       : std::clamp(double(iteration - hold) / (options_.iterations - hold), 0.0, 1.0);
  const double lr = std::exp(std::log(options_.position_lr_init) * (1 - t) + std::log(options_.position_lr_final) * t);
  return lr * extent_;
}

void Trainer::check_finite_array(const std::vector<float>& a, ParamGroup group, int stride, const char* what) const {
  // Per chunk the first bad index; the lowest chunk wins, so the message is thread-independent.
  {
    const int64_t n = int64_t(a.size());
    std::vector<int64_t> first(size_t(num_chunks(0, n, kChunk)), -1);
    parallel_for_chunks(0, n, kChunk, [&](int64_t c, int64_t lo, int64_t hi) {
      const int64_t j = first_non_finite(a.data() + lo, hi - lo);
      if (j >= 0) first[c] = lo + j;
    });
    for (int64_t f : first)
      if (f >= 0) {
        std::ostringstream s;
        s << "training diverged at iteration " << iteration_ << ": non-finite " << what << " "
          << to_string(group_of(group, f)) << " (Gaussian " << f / stride << ", value " << a[f] << ")";
        throw TrainingDiverged(s.str());
      }
  }
}

void Trainer::check_finite_gradients() const {
  auto check = [&](const std::vector<float>& a, ParamGroup group, int stride, const char* what) {
    check_finite_array(a, group, stride, what);
  };
  GaussianSet<float>& gr = const_cast<GaussianSet<float>&>(grad_);
  for_each_array(gr, [&](std::vector<float>& a, ParamGroup group, int stride) { check(a, group, stride, "gradient"); });
}

void Trainer::check_finite_parameters() const {
  GaussianSet<float>& g = const_cast<GaussianSet<float>&>(g_);
  for_each_array(g, [&](std::vector<float>& a, ParamGroup group, int stride) {
    check_finite_array(a, group, stride, "parameter");
  });
}

IterationStats Trainer::step() {
  const int it = ++iteration_;
  // The parameters as the last Adam step left them were checked there (fused into its loop);
  // anything else that changed them (construction, densification, a reset, a checkpoint, a test)
  // cleared the flag.
  if (!parameters_checked_) check_finite_parameters();
  parameters_checked_ = false;
  if (it % options_.sh_degree_interval == 0 && sh_degree_ < options_.max_sh_degree) ++sh_degree_;
  const int view_index = view_for_iteration(it);
  const int factor = downsample_factor(options_.downsample_start, options_.full_resolution_at, options_.iterations, it);
  int level = -1;
  while ((2 << (level + 1)) <= factor) ++level;  // factor 2^(level + 1); -1 at full resolution
  const TrainView& view = level < 0 ? views_[view_index] : lowres_[size_t(level)][view_index];
  RasterCamera<float> cam = RasterCamera<float>::from(view.camera);
  cam.low_pass = float(kLowPass2d / (factor * factor));  // the full-resolution pixel's footprint
  RasterSettings<float> rs;
  rs.sh_degree = sh_degree_;
  for (int c = 0; c < 3; ++c) rs.background[c] = float(options_.background[c]);
  // With distractors, this view sees the scene and its own distractors only (distractors.h).
  const bool subset = num_distractors_ > 0;
  if (subset) {
    rows_for_view(owner_, view_index, &rows_);
    gather_rows(g_, rows_, &sub_);
  }
  const GaussianSet<float>& rendered = subset ? sub_ : g_;
  rasterize_forward(rendered, cam, rs, &state_);
  const std::vector<uint8_t>* invalid = view.invalid.empty() ? nullptr : &view.invalid;
  if (options_.robust == TrainOptions::Robust::kRobustFilter) {
    if (view.invalid.empty()) invalid_.assign(size_t(view.camera.width) * view.camera.height, 0);
    else invalid_ = view.invalid;
    robust_errors_ = robust_pixel_errors(state_.image, view.rgb);
    robust_mask_.exclude(robust_errors_, view.camera.width, view.camera.height, it, options_.seed, &invalid_);
    invalid = &invalid_;
  }
  const bool wild = !wild_.empty();
  if (wild) wild_.forward(view_index, it, state_.image, view.rgb, &wild_render_, &wild_target_);
  const LossValue<float> lv = photometric_loss<float>(wild ? wild_render_ : state_.image, wild ? wild_target_ : view.rgb,
                                                      invalid, view.camera.width, view.camera.height,
                                                      float(options_.lambda_dssim), &v_image_, options_.mask_normalization);
  if (wild && std::isfinite(lv.loss)) wild_.backward_and_step(view_index, it, state_.image, view.rgb, &v_image_);
  if (!std::isfinite(lv.loss)) {
    std::ostringstream s;
    s << "training diverged at iteration " << it << ": non-finite loss (" << lv.loss << ") on view '"
      << view.camera.name << "'";
    throw TrainingDiverged(s.str());
  }
  if (subset) {
    rasterize_backward(sub_, cam, rs, &state_, v_image_, &sub_grad_, &v_ndc_);
    scatter_rows(sub_grad_, rows_, g_.size(), &grad_);
    // The distractors' opacity penalty (distractors.h): weight x the image fraction their opacity
    // covers, each distractor's footprint being 1/distractors_per_view of the image at placement.
    const float w = float(options_.distractor_opacity_weight / options_.distractors_per_view);
    if (w > 0)
      for (int64_t i : rows_)
        if (owner_[size_t(i)] == view_index) {
          const float sg = 1.f / (1.f + std::exp(-g_.opacity_logit[size_t(i)]));
          grad_.opacity_logit[size_t(i)] += w * sg * (1.f - sg);
        }
  } else {
    rasterize_backward(g_, cam, rs, &state_, v_image_, &grad_, &v_ndc_);
  }

  IterationStats stats;
  stats.iteration = it;
  stats.loss = lv.loss;
  stats.psnr = psnr_from_mse(lv.mse);
  stats.downsample = factor;
  bool skip_adam = false;
  // The reference updates its error statistics with the running densification statistics only.
  if (options_.robust == TrainOptions::Robust::kRobustFilter && it < options_.densify_until)
    robust_mask_.update(robust_errors_);
  // The gradients are checked before anything uses them: here when Adam will not run in this
  // iteration, else inside Adam (which reads them anyway), before densification statistics or
  // parameters built from non-finite values can outlive the exception.
  const bool densify_now = it < options_.densify_until && it > options_.densify_from &&
                           it % options_.densification_interval == 0;
  const bool white = options_.background[0] == 1 && options_.background[1] == 1 && options_.background[2] == 1;
  const bool reset_now = it < options_.densify_until &&
                         (it % options_.opacity_reset_interval == 0 || (white && it == options_.densify_from));
  if (densify_now || reset_now) check_finite_gradients();
  if (it < options_.densify_until) {
    const int64_t n = int64_t(rendered.size());
    for (int64_t k = 0; k < n; ++k) {
      if (state_.radius[k] <= 0) continue;
      const int64_t i = subset ? rows_[k] : k;
      max_radii_[i] = std::max(max_radii_[i], float(state_.radius[k]));
      grad_accum_[i] += std::hypot(v_ndc_[k * 2], v_ndc_[k * 2 + 1]);
      grad_count_[i] += 1;
    }
    if (densify_now) {
      densify_and_prune(it > options_.large_prune_from, factor);
      stats.densified = true;
      // The reference replaces every parameter tensor here, leaving them without gradients, so
      // its optimizer.step() of this iteration updates nothing.
      skip_adam = true;
    }
    // As the reference: also reset once at densify_from when training on a white background.
    if (reset_now) {
      reset_opacity();
      skip_adam = true;
    }
  }
  if (!skip_adam && !adam_step()) {
    // Adam met a non-finite gradient or produced a non-finite parameter: name the first one.
    check_finite_gradients();
    check_finite_parameters();
    WGS_CHECK(!"Adam reported a non-finite value that the scans did not find");
  }
  parameters_checked_ = !skip_adam;
  // The blend-weight prune only removes rows: what is left is as Adam (or densification) left it.
  if (std::binary_search(options_.blend_prune_at.begin(), options_.blend_prune_at.end(), it))
    prune_by_blend_weight(options_.blend_prune_threshold);
  stats.num_gaussians = int64_t(g_.size());
  return stats;
}

int64_t Trainer::prune_by_blend_weight(double threshold) {
  const size_t n = g_.size();
  std::vector<float> best(n, 0.f), w;
  RasterSettings<float> rs;
  rs.sh_degree = sh_degree_;  // the weights do not depend on the colours; the image is not used
  rs.outputs = RasterOutputs::kImage;
  RasterState<float> st;
  const bool subset = num_distractors_ > 0;
  for (size_t v = 0; v < views_.size(); ++v) {
    if (subset) {
      rows_for_view(owner_, int(v), &rows_);
      gather_rows(g_, rows_, &sub_);
    }
    rasterize_forward(subset ? sub_ : g_, RasterCamera<float>::from(views_[v].camera), rs, &st);
    max_blend_weights(st, &w);
    for (size_t k = 0; k < w.size(); ++k) {
      const size_t i = subset ? size_t(rows_[k]) : k;
      best[i] = std::max(best[i], w[k]);
    }
  }
  std::vector<char> keep(n);
  for (size_t i = 0; i < n; ++i) keep[i] = best[i] >= float(threshold);
  auto keep_rows = [&](auto& a) {
    size_t kept = 0;
    for (size_t i = 0; i < n; ++i)
      if (keep[i]) a[kept++] = a[i];
    a.resize(kept);
  };
  g_.keep(keep);
  adam_m_.keep(keep);
  adam_v_.keep(keep);
  keep_rows(grad_accum_);
  keep_rows(grad_count_);
  keep_rows(max_radii_);
  keep_rows(owner_);
  num_distractors_ = 0;
  for (const int32_t o : owner_) num_distractors_ += o != kSceneOwner;
  return int64_t(n - g_.size());
}

bool Trainer::adam_step() {
  const double b1 = options_.adam_beta1, b2 = options_.adam_beta2;
  std::array<float, 6> lr{}, step_size{}, bc2_sqrt{};
  lr[int(ParamGroup::kPosition)] = float(position_lr(iteration_));
  lr[int(ParamGroup::kShDc)] = float(options_.feature_lr);
  lr[int(ParamGroup::kShRest)] = float(options_.feature_lr / 20.0);
  lr[int(ParamGroup::kOpacity)] = float(options_.opacity_lr);
  lr[int(ParamGroup::kScale)] = float(options_.scaling_lr);
  lr[int(ParamGroup::kRotation)] = float(options_.rotation_lr);
  for (int k = 0; k < 6; ++k) {
    const int64_t t = ++adam_steps_[k];
    step_size[k] = float(lr[k] / (1.0 - std::pow(b1, double(t))));
    bc2_sqrt[k] = float(std::sqrt(1.0 - std::pow(b2, double(t))));
  }
  AdamConstants constants;
  constants.beta1 = float(b1);
  constants.beta2 = float(b2);
  constants.eps = float(options_.adam_eps);
  auto rates = [&](ParamGroup k) { return AdamRates{step_size[int(k)], bc2_sqrt[int(k)]}; };
  std::vector<std::vector<float>*> params, grads, ms, vs;
  std::vector<ParamGroup> groups;
  auto collect = [&](GaussianSet<float>& s, std::vector<std::vector<float>*>* out) {
    for_each_array(s, [&](std::vector<float>& a, ParamGroup group, int) {
      out->push_back(&a);
      if (out == &params) groups.push_back(group);
    });
  };
  collect(g_, &params);
  collect(grad_, &grads);
  collect(adam_m_, &ms);
  collect(adam_v_, &vs);
  std::atomic<bool> finite{true};  // a flag only: which value is bad, the scans say afterwards
  for (size_t a = 0; a < params.size(); ++a) {
    float* p = params[a]->data();
    const float* gr = grads[a]->data();
    float* m = ms[a]->data();
    float* v = vs[a]->data();
    const ParamGroup group = groups[a];
    // Within an SH row the first 3 floats (DC) and the other 45 use different rates.
    if (group == ParamGroup::kShDc) {
      const int64_t rows = int64_t(params[a]->size()) / kShFloats;
      parallel_for_chunks(0, rows, kChunk, [&](int64_t, int64_t lo, int64_t hi) {
        const int64_t o = lo * kShFloats;
        if (!adam_update_rows(p + o, gr + o, m + o, v + o, hi - lo, kShFloats, 3, constants,
                              rates(ParamGroup::kShDc), rates(ParamGroup::kShRest)))
          finite.store(false, std::memory_order_relaxed);
      });
    } else {
      parallel_for_chunks(0, int64_t(params[a]->size()), kChunk, [&](int64_t, int64_t lo, int64_t hi) {
        if (!adam_update(p + lo, gr + lo, m + lo, v + lo, hi - lo, constants, rates(group)))
          finite.store(false, std::memory_order_relaxed);
      });
    }
  }
  return finite.load();
}

void Trainer::reset_opacity() {
  // opacity = min(opacity, 0.01), with fresh Adam moments for the opacity.
  const float cap = float(inverse_sigmoid(0.01));
  for (size_t i = 0; i < g_.size(); ++i) {
    g_.opacity_logit[i] = std::min(g_.opacity_logit[i], cap);
    adam_m_.opacity_logit[i] = 0.f;
    adam_v_.opacity_logit[i] = 0.f;
  }
}

void Trainer::densify_and_prune(bool prune_large, int factor) {
  const size_t n = g_.size();
  const float threshold = float(options_.densify_grad_threshold);
  const float dense = float(options_.percent_dense * extent_);
  std::vector<char> clone(n, 0), split(n, 0);
  size_t num_clone = 0, num_split = 0;
  for (size_t i = 0; i < n; ++i) {
    const float avg = grad_count_[i] > 0 ? grad_accum_[i] / float(grad_count_[i]) : 0.f;
    if (!(avg >= threshold)) continue;
    const float max_scale = std::exp(std::max({g_.log_scale[i * 3], g_.log_scale[i * 3 + 1], g_.log_scale[i * 3 + 2]}));
    if (max_scale <= dense) clone[i] = 1, ++num_clone;
    else split[i] = 1, ++num_split;
  }
  // The memory guard: a clone adds one Gaussian, a split adds one net (two copies replace the
  // original). Over budget, keep the candidates with the largest mean gradient.
  // Downsampled, the budget shrinks with the pixels (DashGaussian's primitive schedule): a small
  // image holds as many Gaussians per pixel as the full one, no more.
  const int64_t budget = std::max<int64_t>(1, options_.max_gaussians / (int64_t(factor) * factor)) - int64_t(n);
  if (int64_t(num_clone + num_split) > std::max<int64_t>(budget, 0)) {
    std::vector<std::pair<float, size_t>> ranked;
    for (size_t i = 0; i < n; ++i)
      if (clone[i] || split[i]) ranked.push_back({grad_accum_[i] / float(grad_count_[i]), i});
    std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
      return a.first != b.first ? a.first > b.first : a.second < b.second;
    });
    for (size_t k = size_t(std::max<int64_t>(budget, 0)); k < ranked.size(); ++k) {
      const size_t i = ranked[k].second;
      num_clone -= clone[i];
      num_split -= split[i];
      clone[i] = split[i] = 0;
    }
    ++densify_capped_;
  }
  // Layout after densification, as the reference builds it: [originals, clones, split copy 0 of
  // every selected, split copy 1 of every selected]; then the split originals are removed.
  const size_t total = n + num_clone + 2 * num_split;
  std::vector<int32_t> owner(total, kSceneOwner);  // copies keep their original's owner
  GaussianSet<float> out, m, v;
  out.resize(total);
  m.assign_zero(total);
  v.assign_zero(total);
  for (size_t i = 0; i < n; ++i) {
    out.copy_from(g_, i, i);
    m.copy_from(adam_m_, i, i);
    v.copy_from(adam_v_, i, i);
    owner[i] = owner_[i];
  }
  size_t w = n;
  for (size_t i = 0; i < n; ++i)
    if (clone[i]) owner[w] = owner_[i], out.copy_from(g_, i, w++);
  const float log_shrink = float(std::log(0.8 * 2));
  for (int copy = 0; copy < 2; ++copy) {
    for (size_t i = 0; i < n; ++i) {
      if (!split[i]) continue;
      out.copy_from(g_, i, w);
      owner[w] = owner_[i];
      Rng rng(options_.seed, kStreamSplit ^ (uint64_t(iteration_) << 8), uint64_t(i) * 2 + copy);
      Vec3<float> sample;
      for (int k = 0; k < 3; ++k) sample[k] = float(rng.normal()) * std::exp(g_.log_scale[i * 3 + k]);
      const Vec4<float> q(g_.rotation[i * 4], g_.rotation[i * 4 + 1], g_.rotation[i * 4 + 2], g_.rotation[i * 4 + 3]);
      const Vec3<float> offset = quat_to_rotmat(q) * sample;
      for (int k = 0; k < 3; ++k) {
        out.position[w * 3 + k] += offset[k];
        out.log_scale[w * 3 + k] -= log_shrink;
      }
      ++w;
    }
  }
  WGS_CHECK_EQ(w, total);
  std::vector<char> keep(total, 1);
  for (size_t i = 0; i < n; ++i)
    if (split[i]) keep[i] = 0;
  const float min_logit = float(inverse_sigmoid(std::max(options_.min_opacity, 1e-30)));
  const float max_world = float(options_.max_world_size * extent_);
  const bool by_distance = options_.large_prune == TrainOptions::LargePrune::kDistance;
  for (size_t i = 0; i < total; ++i) {
    if (out.opacity_logit[i] < min_logit) keep[i] = 0;
    // Screen-size pruning (max_radii2D > max_screen_size_px) is not applied: the reference resets
    // max_radii2D to zero while densifying, just before this test, so it never fires there either.
    if (prune_large) {
      const float max_scale = std::exp(std::max({out.log_scale[i * 3], out.log_scale[i * 3 + 1], out.log_scale[i * 3 + 2]}));
      float limit = max_world;
      if (by_distance) {  // the larger of the extent and the distance from the rig (TrainOptions::LargePrune)
        const Eigen::Vector3d p(out.position[i * 3], out.position[i * 3 + 1], out.position[i * 3 + 2]);
        limit = std::max(limit, float(options_.max_world_size * (p - rig_center_).norm()));
      }
      if (max_scale > limit) keep[i] = 0;
    }
  }
  out.keep(keep);
  m.keep(keep);
  v.keep(keep);
  size_t kept = 0;
  num_distractors_ = 0;
  for (size_t i = 0; i < total; ++i)
    if (keep[i]) num_distractors_ += owner[i] != kSceneOwner, owner[kept++] = owner[i];
  owner.resize(kept);
  owner_ = std::move(owner);
  g_ = std::move(out);
  adam_m_ = std::move(m);
  adam_v_ = std::move(v);
  grad_accum_.assign(g_.size(), 0.f);
  grad_count_.assign(g_.size(), 0);
  max_radii_.assign(g_.size(), 0.f);
}

GaussianSet<float> Trainer::scene_gaussians() const {
  return num_distractors_ > 0 ? scene_rows(g_, owner_) : g_;
}

}  // namespace weathergs::reconstruction
