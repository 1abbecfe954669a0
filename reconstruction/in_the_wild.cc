#include "reconstruction/in_the_wild.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace weathergs::reconstruction {

namespace {

constexpr float kBeta1 = 0.9f, kBeta2 = 0.999f, kEps = 1e-8f;
// Logit of the map at the start: sigmoid(4) = 0.982, everything visible (a map at exactly 1 would
// have no gradient through the sigmoid).
constexpr float kInitialLogit = 4.f;

void adam(std::vector<float>& p, std::vector<float>& m, std::vector<float>& v, const std::vector<float>& g, float lr,
          int64_t t) {
  const float bc1 = 1.f - std::pow(kBeta1, float(t)), bc2 = 1.f - std::pow(kBeta2, float(t));
  for (size_t i = 0; i < p.size(); ++i) {
    m[i] = kBeta1 * m[i] + (1 - kBeta1) * g[i];
    v[i] = kBeta2 * v[i] + (1 - kBeta2) * g[i] * g[i];
    p[i] -= lr * (m[i] / bc1) / (std::sqrt(v[i] / bc2) + kEps);
  }
}

// Bilinear tap of pixel (x, y) on a grid of cells of `cell` pixels (corners at multiples of cell).
struct Tap {
  int i0, j0;
  float fx, fy;
};
Tap tap(int x, int y, int cell) {
  const float gx = (x + 0.5f) / cell, gy = (y + 0.5f) / cell;
  Tap t{int(gx), int(gy), 0, 0};
  t.fx = gx - t.i0, t.fy = gy - t.j0;
  return t;
}

}  // namespace

InTheWild::InTheWild(const std::vector<TrainView>& views, const InTheWildOptions& o) : options_(o) {
  WGS_CHECK(o.cell_px >= 1 && o.from >= 0);
  for (const TrainView& tv : views) {
    View v;
    v.width = tv.camera.width, v.height = tv.camera.height;
    v.gw = v.width / o.cell_px + 2, v.gh = v.height / o.cell_px + 2;
    v.affine = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};
    v.affine_m.assign(12, 0.f);
    v.affine_v.assign(12, 0.f);
    v.logits.assign(size_t(v.gw) * v.gh, kInitialLogit);
    v.logits_m.assign(v.logits.size(), 0.f);
    v.logits_v.assign(v.logits.size(), 0.f);
    views_.push_back(std::move(v));
  }
}

void InTheWild::upsample(const View& v, std::vector<float>* m) const {
  m->resize(size_t(v.width) * v.height);
  for (int y = 0; y < v.height; ++y)
    for (int x = 0; x < v.width; ++x) {
      const Tap t = tap(x, y, options_.cell_px);
      const float* l = &v.logits[size_t(t.j0) * v.gw + t.i0];
      const float z = (1 - t.fy) * ((1 - t.fx) * l[0] + t.fx * l[1]) + t.fy * ((1 - t.fx) * l[v.gw] + t.fx * l[v.gw + 1]);
      (*m)[size_t(y) * v.width + x] = 1.f / (1.f + std::exp(-z));
    }
}

std::vector<float> InTheWild::visibility(int view) const {
  std::vector<float> m;
  upsample(views_[size_t(view)], &m);
  return m;
}

void InTheWild::forward(int view, int iteration, const std::vector<float>& render, const std::vector<float>& target,
                        std::vector<float>* render_out, std::vector<float>* target_out) {
  const View& v = views_[size_t(view)];
  const size_t n = size_t(v.width) * v.height;
  WGS_CHECK(render.size() == n * 3 && target.size() == n * 3);
  const bool masked = iteration > options_.from;
  if (masked) upsample(v, &mask_);
  render_out->resize(n * 3);
  target_out->resize(n * 3);
  const float* a = v.affine.data();
  for (size_t p = 0; p < n; ++p) {
    const float* c = &render[p * 3];
    const float mk = masked ? mask_[p] : 1.f;
    for (int r = 0; r < 3; ++r) {
      (*render_out)[p * 3 + r] = mk * (a[3 * r] * c[0] + a[3 * r + 1] * c[1] + a[3 * r + 2] * c[2] + a[9 + r]);
      (*target_out)[p * 3 + r] = mk * target[p * 3 + r];
    }
  }
}

double InTheWild::regulariser(int view, int iteration) const {
  if (iteration <= options_.from) return 0;
  std::vector<float> m;
  upsample(views_[size_t(view)], &m);
  double s = 0;
  for (float x : m) s += double(1 - x) * (1 - x);
  return options_.visibility_weight * s / double(m.size());
}

void InTheWild::backward(int view, int iteration, const std::vector<float>& render, const std::vector<float>& target,
                         std::vector<float>* v_io) {
  View& v = views_[size_t(view)];
  const size_t n = size_t(v.width) * v.height;
  std::vector<float>& g = *v_io;
  const bool masked = iteration > options_.from;
  if (masked) upsample(v, &mask_);
  std::vector<double> ga(12, 0.0);
  grad_logits_.assign(v.logits.size(), 0.f);
  const float* a = v.affine.data();
  // L1 share of the map's gradient: d/dM of (1 - lambda) mean |M (a - t)| = (1 - lambda) |a - t| / (3 n).
  const float l1_scale = float((1 - options_.lambda_dssim) / (3.0 * double(n)));
  const float reg_scale = float(2 * options_.visibility_weight / double(n));
  for (size_t p = 0; p < n; ++p) {
    const float* c = &render[p * 3];
    const float mk = masked ? mask_[p] : 1.f;
    float gm = 0, out[3];
    for (int r = 0; r < 3; ++r) {
      const float gr = mk * g[p * 3 + r];  // d loss / d (A c + b)
      for (int k = 0; k < 3; ++k) ga[size_t(3 * r + k)] += double(gr) * c[k];
      ga[size_t(9 + r)] += gr;
      out[r] = gr;
      if (masked) gm += std::abs(a[3 * r] * c[0] + a[3 * r + 1] * c[1] + a[3 * r + 2] * c[2] + a[9 + r] - target[p * 3 + r]);
    }
    for (int k = 0; k < 3; ++k) g[p * 3 + k] = a[k] * out[0] + a[3 + k] * out[1] + a[6 + k] * out[2];  // A^T
    if (masked) {
      const float dm = (l1_scale * gm - reg_scale * (1 - mk)) * mk * (1 - mk);  // through the sigmoid
      const int x = int(p % size_t(v.width)), y = int(p / size_t(v.width));
      const Tap t = tap(x, y, options_.cell_px);
      float* gl = &grad_logits_[size_t(t.j0) * v.gw + t.i0];
      gl[0] += (1 - t.fx) * (1 - t.fy) * dm;
      gl[1] += t.fx * (1 - t.fy) * dm;
      gl[v.gw] += (1 - t.fx) * t.fy * dm;
      gl[v.gw + 1] += t.fx * t.fy * dm;
    }
  }
  grad_affine_.assign(ga.begin(), ga.end());
}

void InTheWild::step(int view, int iteration) {
  View& v = views_[size_t(view)];
  ++v.steps;
  adam(v.affine, v.affine_m, v.affine_v, grad_affine_, float(options_.appearance_lr), v.steps);
  if (iteration > options_.from)
    adam(v.logits, v.logits_m, v.logits_v, grad_logits_, float(options_.visibility_lr), ++v.mask_steps);
}

size_t InTheWild::state_size() const {
  size_t s = 0;
  for (const View& v : views_) s += 2 + 36 + 3 * v.logits.size();
  return s;
}

std::vector<float> InTheWild::state() const {
  std::vector<float> s;
  s.reserve(state_size());
  for (const View& v : views_) {
    s.push_back(float(v.steps));  // exact below 2^24 steps
    s.push_back(float(v.mask_steps));
    for (const std::vector<float>* a : {&v.affine, &v.affine_m, &v.affine_v, &v.logits, &v.logits_m, &v.logits_v})
      s.insert(s.end(), a->begin(), a->end());
  }
  return s;
}

void InTheWild::restore(const std::vector<float>& s) {
  if (s.size() != state_size())
    throw InputError("checkpoint", "in-the-wild state holds " + std::to_string(s.size()) + " values, expected " +
                                       std::to_string(state_size()));
  size_t off = 0;
  for (View& v : views_) {
    v.steps = int64_t(s[off++]);
    v.mask_steps = int64_t(s[off++]);
    for (std::vector<float>* a : {&v.affine, &v.affine_m, &v.affine_v, &v.logits, &v.logits_m, &v.logits_v}) {
      std::copy(s.begin() + long(off), s.begin() + long(off + a->size()), a->begin());
      off += a->size();
    }
  }
}

}  // namespace weathergs::reconstruction
