#include "nerf/trainer.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/json_fields.h"
#include "core/parallel.h"
#include "core/rng.h"

namespace weathergs::nerf {

namespace {

// Rng streams (the index is iteration * batch + ray, or iteration * tv points + k).
constexpr uint64_t kStreamRay = 1, kStreamJitter = 2, kStreamTv = 3;
constexpr int64_t kRayChunk = 128;  // rays per work item (fixed: results never depend on threads)
constexpr int kSlabs = 32;          // lattice slabs along w that apply gradients in parallel
constexpr float kBeta1 = 0.9f, kBeta2 = 0.99f, kAdamEps = 1e-8f;  // DVGO's MaskedAdam
constexpr float kPrunedRaw = -20.f;  // raw density of lattice points no training camera sees

}  // namespace

void NerfOptions::validate(const std::string& where) const {
  auto fail = [&](const std::string& field, const std::string& rule) { throw InputError(where, field + " " + rule); };
  if (iterations < 1) fail("iterations", "must be >= 1");
  if (batch_rays < 1 || batch_rays > (1 << 20)) fail("batch_rays", "must be in [1, 1048576]");
  if (!(pixels_per_cell >= 0.25 && pixels_per_cell <= 64)) fail("pixels_per_cell", "must be in [0.25, 64]");
  if (depth_cells < 2 || depth_cells > 2048) fail("depth_cells", "must be in [2, 2048]");
  if (level_scales.empty() || level_scales.back() != 1.0) fail("level_scales", "must end with 1");
  for (size_t i = 0; i < level_scales.size(); ++i)
    if (!(level_scales[i] > 0 && level_scales[i] <= 1) || (i > 0 && level_scales[i] <= level_scales[i - 1]))
      fail("level_scales", "must increase within (0, 1]");
  if (upsample_at.size() + 1 != level_scales.size()) fail("upsample_at", "must hold one iteration per level after the first");
  for (size_t i = 0; i < upsample_at.size(); ++i)
    if (upsample_at[i] < 1 || (i > 0 && upsample_at[i] <= upsample_at[i - 1])) fail("upsample_at", "must increase from >= 1");
  if (!(alpha_init > 0 && alpha_init < 1)) fail("alpha_init", "must be in (0, 1)");
  for (double lr : {lr_density, lr_color, lr_env})
    if (!(lr > 0 && std::isfinite(lr))) fail("lr_density/lr_color/lr_env", "must be > 0");
  if (!(lr_final_factor > 0 && lr_final_factor <= 1)) fail("lr_final_factor", "must be in (0, 1]");
  if (!(tv_density >= 0 && tv_color >= 0 && std::isfinite(tv_density + tv_color))) fail("tv_density/tv_color", "must be >= 0");
  if (!(tv_fraction >= 0 && tv_fraction <= 1)) fail("tv_fraction", "must be in [0, 1]");
  if (!(near_m >= 0 && std::isfinite(near_m))) fail("near_m", "must be >= 0 (0 = from the SfM points)");
  if (march.samples_per_cell < 1 || march.samples_per_cell > 16) fail("march.samples_per_cell", "must be in [1, 16]");
  if (!(march.min_weight >= 0 && march.min_weight < 1)) fail("march.min_weight", "must be in [0, 1)");
  if (!(march.min_transmittance >= 0 && march.min_transmittance < 1)) fail("march.min_transmittance", "must be in [0, 1)");
}

namespace {
// Every key required: a radiance-field run records all of its options.
constexpr auto kNerfFields = [](auto& s, auto& f) {
  f("iterations", s.iterations);
  f("batch_rays", s.batch_rays);
  f("seed", s.seed);
  f("pixels_per_cell", s.pixels_per_cell);
  f("depth_cells", s.depth_cells);
  f("level_scales", s.level_scales);
  f("upsample_at", s.upsample_at);
  f("alpha_init", s.alpha_init);
  f("lr_density", s.lr_density);
  f("lr_color", s.lr_color);
  f("lr_env", s.lr_env);
  f("lr_final_factor", s.lr_final_factor);
  f("tv_density", s.tv_density);
  f("tv_color", s.tv_color);
  f("tv_fraction", s.tv_fraction);
  f("near_m", s.near_m);
  f("samples_per_cell", s.march.samples_per_cell);
  f("min_weight", s.march.min_weight);
  f("min_transmittance", s.march.min_transmittance);
};
}  // namespace

Json NerfOptions::to_json() const { return json_fields::write(*this, kNerfFields); }

NerfOptions NerfOptions::from_json(const JsonReader& r) {
  NerfOptions o = json_fields::read(r, NerfOptions{}, kNerfFields, json_fields::Absent::kError);
  o.validate(r.where());
  return o;
}

NerfOptions NerfOptions::from_user_json(const JsonReader& r) {
  NerfOptions o = json_fields::read(r, NerfOptions{}, kNerfFields, json_fields::Absent::kDefaults);
  o.validate(r.where());
  return o;
}

NerfTrainer::NerfTrainer(std::vector<TrainView> views, const FrustumFrame& frame, const NerfOptions& options)
    : views_(std::move(views)), options_(options) {
  options_.validate("nerf options");
  WGS_CHECK(!views_.empty());
  const Camera& c0 = views_[0].camera;
  pixels_per_view_ = int64_t(c0.width) * c0.height;
  double f = 0;
  for (size_t v = 0; v < views_.size(); ++v) {
    const Camera& c = views_[v].camera;
    if (int64_t(c.width) * c.height != pixels_per_view_)
      throw InputError("camera '" + c.name + "'", "every training view must have the same size for the radiance field");
    f += 0.5 * (c.fx + c.fy);
    const std::vector<uint8_t>& inv = views_[v].invalid;
    for (int64_t p = 0; p < pixels_per_view_; ++p)
      if (inv.empty() || !inv[size_t(p)]) valid_.push_back(int64_t(v) * pixels_per_view_ + p);
  }
  if (valid_.empty()) throw InputError("nerf training", "every pixel of every training view is masked out");
  f /= double(views_.size());
  const double cells_u = (frame.u1 - frame.u0) * f / options_.pixels_per_cell;
  const double cells_v = (frame.v1 - frame.v0) * f / options_.pixels_per_cell;
  final_dims_ = GridDims{std::max(2, int(std::lround(cells_u)) + 1), std::max(2, int(std::lround(cells_v)) + 1),
                         options_.depth_cells + 1};
  field_ = RadianceField(frame, level_dims(0), options_.alpha_init);
  prune_unseen();
  start_level(0);
}

GridDims NerfTrainer::level_dims(int level) const {
  const double s = options_.level_scales[size_t(level)];
  auto scaled = [&](int n) { return std::max(2, int(std::lround((n - 1) * s)) + 1); };
  return GridDims{scaled(final_dims_.nu), scaled(final_dims_.nv), scaled(final_dims_.nw)};
}

void NerfTrainer::start_level(int level) {
  if (level > 0) field_ = field_.resampled(level_dims(level));
  level_ = level;
  const size_t n = size_t(field_.dims().points()) * kStride;
  grad_.assign(n, 0.f);
  m_.assign(n, 0.f);
  v_.assign(n, 0.f);
  touched_.assign(size_t(field_.dims().points()), 0);
  env_grad_.assign(field_.env().size(), 0.f);
  env_m_.assign(field_.env().size(), 0.f);
  env_v_.assign(field_.env().size(), 0.f);
  adam_steps_ = 0;  // a fresh optimizer per level, as DVGO after each scale-up
}

// Lattice points that no training camera sees get no gradient and would keep their initial fog:
// they start (nearly) empty instead.
void NerfTrainer::prune_unseen() {
  const FrustumFrame& fr = field_.frame();
  const GridDims& d = field_.dims();
  const Eigen::Matrix3d world_from_ref = fr.ref_from_world.transpose();
  std::vector<float>& p = field_.params();
  parallel_for(0, d.nw, [&](int64_t k) {
    const double w = double(k) / (d.nw - 1) * fr.w_max;
    for (int j = 0; j < d.nv; ++j)
      for (int i = 0; i < d.nu; ++i) {
        const double u = fr.u0 + (fr.u1 - fr.u0) * i / (d.nu - 1), v = fr.v0 + (fr.v1 - fr.v0) * j / (d.nv - 1);
        bool seen = false;
        for (const TrainView& tv : views_) {
          const Camera& c = tv.camera;
          Eigen::Vector3d pc;
          if (w > 0) {
            pc = c.to_camera(world_from_ref * Eigen::Vector3d(u / w, v / w, 1.0 / w) + fr.center);
          } else {
            pc = c.rotation() * (world_from_ref * Eigen::Vector3d(u, v, 1.0));  // a direction at the horizon
          }
          if (pc.z() <= 0) continue;
          const Eigen::Vector2d px = c.project_camera(pc);
          const double margin = 2;
          if (px.x() >= -margin && px.y() >= -margin && px.x() <= c.width + margin && px.y() <= c.height + margin) {
            seen = true;
            break;
          }
        }
        if (!seen) p[size_t(field_.index(i, j, int(k))) * kStride] = kPrunedRaw;
      }
  });
  field_.rebuild_occupancy();
}

NerfIterationStats NerfTrainer::step() {
  if (level_ + 1 < int(options_.level_scales.size()) && iteration_ == options_.upsample_at[size_t(level_)])
    start_level(level_ + 1);
  const int64_t batch = options_.batch_rays;
  const int64_t chunks = num_chunks(0, batch, kRayChunk);
  const GridDims dims = field_.dims();
  struct ChunkOut {
    std::vector<std::vector<SampleGrad>> slab;  // per slab, in ray order
    std::vector<float> env;
    double loss = 0;
    int64_t samples = 0;
  };
  std::vector<ChunkOut> out(static_cast<size_t>(chunks));
  const int lattice_w = dims.nw;
  auto slab_of = [&](int k) { return int(int64_t(k) * kSlabs / lattice_w); };
  parallel_for_chunks(0, batch, kRayChunk, [&](int64_t chunk, int64_t lo, int64_t hi) {
    ChunkOut& co = out[size_t(chunk)];
    co.slab.assign(kSlabs, {});
    co.env.assign(field_.env().size(), 0.f);
    std::vector<RaySample> samples;
    std::vector<SampleGrad> grads;
    for (int64_t r = lo; r < hi; ++r) {
      const uint64_t key = uint64_t(iteration_) * uint64_t(batch) + uint64_t(r);
      Rng pick(options_.seed, kStreamRay, key);
      const int64_t id = valid_[pick.uniform_int(uint32_t(valid_.size()))];
      const TrainView& view = views_[size_t(id / pixels_per_view_)];
      const int64_t pix = id % pixels_per_view_;
      const int x = int(pix % view.camera.width), y = int(pix / view.camera.width);
      Rng jit(options_.seed, kStreamJitter, key);
      const RayResult res = field_.march(pixel_ray(view.camera, x, y), jit.uniform(), options_.march, &samples);
      float g[3];
      for (int ch = 0; ch < 3; ++ch) {
        const float e = res.rgb[ch] - view.rgb[size_t(pix) * 3 + ch];
        co.loss += double(e) * e;
        g[ch] = 2.f * e / float(3 * batch);  // d mean over rays and channels of squared error
      }
      co.samples += int64_t(samples.size());
      grads.clear();
      float env_grad[3];
      field_.march_backward(samples, res, g, &grads, env_grad);
      for (const SampleGrad& sg : grads) {
        const int k0 = int(sg.base / (int64_t(dims.nu) * dims.nv));
        const int s0 = slab_of(k0), s1 = slab_of(k0 + 1);
        co.slab[size_t(s0)].push_back(sg);
        if (s1 != s0) co.slab[size_t(s1)].push_back(sg);
      }
      int idx[4];
      float w[4];
      field_.env_taps(view.camera.ray_direction_world(Eigen::Vector2d(x + 0.5, y + 0.5)), idx, w);
      for (int q = 0; q < 4; ++q)
        for (int ch = 0; ch < 3; ++ch) co.env[size_t(idx[q]) * 3 + ch] += w[q] * env_grad[ch];
    }
  });

  // Spread the sample gradients over the lattice: each slab owns its points and applies the chunks
  // in order, so every point sums its contributions in the same order with any thread count.
  parallel_for(0, kSlabs, [&](int64_t s) {
    // Slab s owns the lattice points with w index in [k_lo, k_hi).
    const int k_lo = int((s * lattice_w + kSlabs - 1) / kSlabs), k_hi = int(((s + 1) * lattice_w + kSlabs - 1) / kSlabs);
    for (const ChunkOut& co : out)
      for (const SampleGrad& sg : co.slab[size_t(s)]) spread_sample_grad(sg, dims, k_lo, k_hi, grad_.data(), touched_.data());
  });
  NerfIterationStats st;
  double loss = 0;
  for (const ChunkOut& co : out) {
    loss += co.loss;
    st.samples += co.samples;
    for (size_t q = 0; q < env_grad_.size(); ++q) env_grad_[q] += co.env[q];
  }
  st.loss = loss / double(3 * batch);
  if (!std::isfinite(st.loss))
    throw NumericalDivergence("nerf training: the loss is not finite at iteration " + std::to_string(iteration_ + 1));
  add_tv();
  adam_step();
  ++iteration_;
  st.iteration = iteration_;
  st.psnr = -10 * std::log10(std::max(st.loss, 1e-10));
  st.lattice_points = field_.dims().points();
  st.occupied_cells = field_.occupied_cells();
  return st;
}

void NerfTrainer::add_tv() {
  if (options_.tv_fraction <= 0 || (options_.tv_density <= 0 && options_.tv_color <= 0)) return;
  const GridDims d = field_.dims();
  const int64_t cells = d.cells();
  const int64_t m = std::max<int64_t>(1, int64_t(options_.tv_fraction * double(cells)));
  const std::vector<float>& p = field_.params();
  const int64_t stride[3] = {1, d.nu, int64_t(d.nu) * d.nv};
  const float wd = float(2 * options_.tv_density / double(m)), wc = float(2 * options_.tv_color / double(m));
  for (int64_t n = 0; n < m; ++n) {
    Rng rng(options_.seed, kStreamTv, uint64_t(iteration_) * uint64_t(m) + uint64_t(n));
    const int i = int(rng.uniform_int(uint32_t(d.nu - 1))), j = int(rng.uniform_int(uint32_t(d.nv - 1))),
              k = int(rng.uniform_int(uint32_t(d.nw - 1)));
    const int64_t a = field_.index(i, j, k);
    for (int64_t s : stride) {
      const int64_t b = a + s;
      const float* pa = &p[size_t(a) * kStride];
      const float* pb = &p[size_t(b) * kStride];
      float* ga = &grad_[size_t(a) * kStride];
      float* gb = &grad_[size_t(b) * kStride];
      const float dd = wd * (pa[0] - pb[0]);
      ga[0] += dd, gb[0] -= dd;
      for (int q = 1; q <= 3 * kShCoeffs; ++q) {
        const float dc = wc * (pa[q] - pb[q]);
        ga[q] += dc, gb[q] -= dc;
      }
      touched_[size_t(a)] = touched_[size_t(b)] = 1;
    }
  }
}

void NerfTrainer::adam_step() {
  ++adam_steps_;
  const double progress = double(iteration_) / options_.iterations;
  const double decay = std::pow(options_.lr_final_factor, progress);
  const float bc1 = 1.f - std::pow(kBeta1, float(adam_steps_)), bc2 = 1.f - std::pow(kBeta2, float(adam_steps_));
  const float lr_d = float(options_.lr_density * decay) / bc1, lr_c = float(options_.lr_color * decay) / bc1;
  const float inv_sqrt_bc2 = 1.f / std::sqrt(bc2);
  std::vector<float>& p = field_.params();
  const float active = field_.active_raw();
  const int64_t points = field_.dims().points();
  constexpr int64_t kChunk = 1 << 14;
  std::vector<std::vector<std::pair<int64_t, bool>>> flips(size_t(num_chunks(0, points, kChunk)));
  parallel_for_chunks(0, points, kChunk, [&](int64_t chunk, int64_t lo, int64_t hi) {
    for (int64_t i = lo; i < hi; ++i) {
      if (!touched_[size_t(i)]) continue;
      touched_[size_t(i)] = 0;
      float* pp = &p[size_t(i) * kStride];
      float* g = &grad_[size_t(i) * kStride];
      float* m = &m_[size_t(i) * kStride];
      float* v = &v_[size_t(i) * kStride];
      const bool was = pp[0] >= active;
      for (int q = 0; q <= 3 * kShCoeffs; ++q) {
        m[q] = kBeta1 * m[q] + (1 - kBeta1) * g[q];
        v[q] = kBeta2 * v[q] + (1 - kBeta2) * g[q] * g[q];
        pp[q] -= (q == 0 ? lr_d : lr_c) * m[q] / (std::sqrt(v[q]) * inv_sqrt_bc2 + kAdamEps);
        g[q] = 0;
      }
      const bool is = pp[0] >= active;
      if (was != is) flips[size_t(chunk)].emplace_back(i, is);
    }
  });
  for (const auto& list : flips)
    for (const auto& [i, is] : list) field_.update_occupancy(i, !is, is);
  const float lr_e = float(options_.lr_env * decay) / bc1;
  std::vector<float>& e = field_.env();
  for (size_t q = 0; q < e.size(); ++q) {
    const float g = env_grad_[q];
    env_m_[q] = kBeta1 * env_m_[q] + (1 - kBeta1) * g;
    env_v_[q] = kBeta2 * env_v_[q] + (1 - kBeta2) * g * g;
    e[q] -= lr_e * env_m_[q] / (std::sqrt(env_v_[q]) * inv_sqrt_bc2 + kAdamEps);
    env_grad_[q] = 0;
  }
}

}  // namespace weathergs::nerf
