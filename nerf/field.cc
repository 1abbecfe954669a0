#include "nerf/field.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>

#include "core/atomic_file.h"
#include "core/constants.h"
#include "core/error.h"
#include "core/parallel.h"

namespace weathergs::nerf {

namespace {

constexpr const char* kFieldMagic = "WGSNERF1";
constexpr const char* kFieldFormat = "weathergs-nerf-field";
constexpr int kFieldVersion = 1;
constexpr int kStoredFloats = 1 + 3 * kShCoeffs;  // per point in field.bin (no padding)
// Occupancy skips a cell only when sigma_max * delta < kOccupancyWeight with a margin, and only for
// steps up to max_skip_delta_ cells (longer steps are evaluated): then alpha <= sigma * delta and
// T * alpha < the march's min_weight, so the skipped sample would have been dropped anyway.
constexpr float kOccupancyWeight = 1e-4f;
constexpr float kOccupancyMargin = 0.999f;
constexpr double kMinDirZ = 1e-3;  // rays this close to parallel with the reference image plane miss the grid

// d sigma: the SH basis of degree 1 (3DGS's constants and sign convention).
constexpr float kSh0 = 0.28209479177387814f, kSh1 = 0.4886025119029199f;

void sh_basis(const Eigen::Vector3d& d, float y[kShCoeffs]) {
  y[0] = kSh0;
  y[1] = -kSh1 * float(d.y());
  y[2] = kSh1 * float(d.z());
  y[3] = -kSh1 * float(d.x());
}

// Corner c = (bit 0: +u, bit 1: +v, bit 2: +w) of a cell: the one weight order of the march and of
// the gradient spread.
inline void trilinear_weights(float fu, float fv, float fw, float wt[8]) {
  wt[0] = (1 - fu) * (1 - fv) * (1 - fw), wt[1] = fu * (1 - fv) * (1 - fw);
  wt[2] = (1 - fu) * fv * (1 - fw), wt[3] = fu * fv * (1 - fw);
  wt[4] = (1 - fu) * (1 - fv) * fw, wt[5] = fu * (1 - fv) * fw;
  wt[6] = (1 - fu) * fv * fw, wt[7] = fu * fv * fw;
}

float softplus_inverse(float y) { return y > 20 ? y : std::log(std::expm1(y)); }

}  // namespace

float softplusf(float x) { return x > 20.f ? x : std::log1p(std::exp(x)); }

Ray pixel_ray(const Camera& camera, int x, int y) {
  return Ray{camera.center_world(), camera.ray_direction_world(Eigen::Vector2d(x + 0.5, y + 0.5))};
}

void spread_sample_grad(const SampleGrad& sg, const GridDims& d, int k_lo, int k_hi, float* grad, uint8_t* touched) {
  const int64_t plane = int64_t(d.nu) * d.nv;
  const int k0 = int(sg.base / plane);
  float wt[8];
  trilinear_weights(sg.fu, sg.fv, sg.fw, wt);
  float feat[3 * kShCoeffs];
  for (int b = 0; b < kShCoeffs; ++b)
    for (int ch = 0; ch < 3; ++ch) feat[3 * b + ch] = sg.sh[b] * sg.d_pre[ch];
  for (int c = 0; c < 8; ++c) {
    const int k = k0 + (c >> 2);
    if (k < k_lo || k >= k_hi) continue;
    const int64_t p = sg.base + (c & 1) + ((c >> 1) & 1) * int64_t(d.nu) + (c >> 2) * plane;
    float* gp = grad + p * kStride;
    gp[0] += wt[c] * sg.d_raw;
    for (int q = 0; q < 3 * kShCoeffs; ++q) gp[1 + q] += wt[c] * feat[q];
    touched[p] = 1;
  }
}

RadianceField::RadianceField(const FrustumFrame& frame, const GridDims& dims, double alpha_init)
    : frame_(frame), dims_(dims) {
  WGS_CHECK(dims.nu >= 2 && dims.nv >= 2 && dims.nw >= 2);
  WGS_CHECK(alpha_init > 0 && alpha_init < 1);
  // DVGO's activation shift: softplus(0 + shift) = -log(1 - alpha_init), i.e. alpha = alpha_init per cell.
  shift_ = float(std::log(1.0 / (1.0 - alpha_init) - 1.0));
  const float sigma_min = kOccupancyMargin * kOccupancyWeight / max_skip_delta_;
  active_raw_ = softplus_inverse(sigma_min) - shift_;
  params_.assign(size_t(dims.points()) * kStride, 0.f);
  env_.assign(size_t(kEnvW) * kEnvH * 3, 0.f);
  rebuild_occupancy();
}

Eigen::Vector3d RadianceField::grid_coords(const Eigen::Vector3d& p_world) const {
  const Eigen::Vector3d q = frame_.to_ref(p_world);
  const double w = 1.0 / q.z();
  return Eigen::Vector3d((q.x() * w - frame_.u0) / (frame_.u1 - frame_.u0) * (dims_.nu - 1),
                         (q.y() * w - frame_.v0) / (frame_.v1 - frame_.v0) * (dims_.nv - 1),
                         w / frame_.w_max * (dims_.nw - 1));
}

void RadianceField::rebuild_occupancy() {
  occupancy_.assign(size_t(dims_.cells()), 0);
  for (int k = 0; k < dims_.nw; ++k)
    for (int j = 0; j < dims_.nv; ++j)
      for (int i = 0; i < dims_.nu; ++i)
        if (params_[size_t(index(i, j, k)) * kStride] >= active_raw_) update_occupancy(index(i, j, k), false, true);
}

void RadianceField::update_occupancy(int64_t p, bool was_active, bool is_active) {
  if (was_active == is_active) return;
  const int i = int(p % dims_.nu), j = int((p / dims_.nu) % dims_.nv), k = int(p / (int64_t(dims_.nu) * dims_.nv));
  const int cu = dims_.nu - 1, cv = dims_.nv - 1;
  for (int dk = -1; dk <= 0; ++dk)
    for (int dj = -1; dj <= 0; ++dj)
      for (int di = -1; di <= 0; ++di) {
        const int ci = i + di, cj = j + dj, ck = k + dk;
        if (ci < 0 || cj < 0 || ck < 0 || ci >= cu || cj >= cv || ck >= dims_.nw - 1) continue;
        uint8_t& c = occupancy_[size_t(ci + int64_t(cu) * (cj + int64_t(cv) * ck))];
        if (is_active) {
          WGS_CHECK(c < 8);
          ++c;
        } else {
          WGS_CHECK(c > 0);
          --c;
        }
      }
}

int64_t RadianceField::occupied_cells() const {
  return std::count_if(occupancy_.begin(), occupancy_.end(), [](uint8_t c) { return c > 0; });
}

RadianceField RadianceField::resampled(const GridDims& d) const {
  RadianceField out = *this;
  out.dims_ = d;
  out.params_.assign(size_t(d.points()) * kStride, 0.f);
  const double su = double(dims_.nu - 1) / (d.nu - 1), sv = double(dims_.nv - 1) / (d.nv - 1),
               sw = double(dims_.nw - 1) / (d.nw - 1);
  parallel_for(0, d.nw, [&](int64_t k) {
    for (int j = 0; j < d.nv; ++j)
      for (int i = 0; i < d.nu; ++i) {
        const double g[3] = {i * su, j * sv, k * sw};
        const int n[3] = {dims_.nu, dims_.nv, dims_.nw};
        int b[3];
        float f[3];
        for (int a = 0; a < 3; ++a) {
          b[a] = std::min(int(g[a]), n[a] - 2);
          f[a] = float(g[a] - b[a]);
        }
        float* dst = &out.params_[size_t(out.index(i, j, int(k))) * kStride];
        for (int c = 0; c < 8; ++c) {
          const int ci = b[0] + (c & 1), cj = b[1] + ((c >> 1) & 1), ck = b[2] + ((c >> 2) & 1);
          const float wgt = ((c & 1) ? f[0] : 1 - f[0]) * (((c >> 1) & 1) ? f[1] : 1 - f[1]) *
                            (((c >> 2) & 1) ? f[2] : 1 - f[2]);
          const float* src = &params_[size_t(index(ci, cj, ck)) * kStride];
          for (int q = 0; q < kStoredFloats; ++q) dst[q] += wgt * src[q];
        }
      }
  });
  out.rebuild_occupancy();
  return out;
}

void RadianceField::env_taps(const Eigen::Vector3d& direction, int idx[4], float w[4]) const {
  const Eigen::Vector3d d = frame_.ref_from_world * direction;
  const double lon = std::atan2(d.x(), d.z()), lat = std::asin(std::clamp(d.y(), -1.0, 1.0));
  const double x = (lon + kPi) / (2 * kPi) * kEnvW - 0.5;
  const double y = std::clamp((lat + kPi / 2) / kPi * kEnvH - 0.5, 0.0, double(kEnvH - 1));
  const int x0 = int(std::floor(x)), y0 = std::min(int(y), kEnvH - 2);
  const float fx = float(x - x0), fy = float(y - y0);
  const int xa = ((x0 % kEnvW) + kEnvW) % kEnvW, xb = (xa + 1) % kEnvW;
  idx[0] = y0 * kEnvW + xa, idx[1] = y0 * kEnvW + xb, idx[2] = (y0 + 1) * kEnvW + xa, idx[3] = (y0 + 1) * kEnvW + xb;
  w[0] = (1 - fx) * (1 - fy), w[1] = fx * (1 - fy), w[2] = (1 - fx) * fy, w[3] = fx * fy;
}

RayResult RadianceField::march(const Ray& ray, float jitter, const MarchSettings& s,
                               std::vector<RaySample>* samples) const {
  RayResult res;
  if (samples) samples->clear();
  float T = 1.f;
  const Eigen::Vector3d o = frame_.to_ref(ray.origin), d = frame_.ref_from_world * ray.direction;
  if (d.z() > kMinDirZ) {
    float sh[kShCoeffs];
    sh_basis(ray.direction, sh);
    const int steps = (dims_.nw - 1) * s.samples_per_cell;
    const double dw = frame_.w_max / steps;
    // Only in front of the camera: t > 0, i.e. Z > o.z, i.e. w < 1 / o.z.
    const double w_start = o.z() > 0 ? std::min(frame_.w_max * (1 + 1e-9), 1.0 / o.z()) : frame_.w_max * (1 + 1e-9);
    const double su = (dims_.nu - 1) / (frame_.u1 - frame_.u0), sv = (dims_.nv - 1) / (frame_.v1 - frame_.v0),
                 sw = (dims_.nw - 1) / frame_.w_max;
    auto coords = [&](double w, double g[3]) {
      if (w <= 0) {  // the horizon: the ray's direction
        g[0] = (d.x() / d.z() - frame_.u0) * su, g[1] = (d.y() / d.z() - frame_.v0) * sv, g[2] = 0;
        return;
      }
      const double t = (1.0 / w - o.z()) / d.z();
      g[0] = ((o.x() + t * d.x()) * w - frame_.u0) * su;
      g[1] = ((o.y() + t * d.y()) * w - frame_.v0) * sv;
      g[2] = w * sw;
    };
    const bool occupancy = s.use_occupancy && s.min_weight >= kOccupancyWeight;
    const int64_t su_stride = kStride, sv_stride = int64_t(dims_.nu) * kStride,
                  sw_stride = int64_t(dims_.nu) * dims_.nv * kStride;
    const int64_t corner[8] = {0,         su_stride,         sv_stride,         su_stride + sv_stride,
                               sw_stride, sw_stride + su_stride, sw_stride + sv_stride, sw_stride + su_stride + sv_stride};
    const int k_first = std::max(0, int(std::floor((frame_.w_max - w_start) / dw - jitter)));
    double g[3], gn[3];
    bool have_g = false;
    for (int k = k_first; k < steps + 1; ++k) {
      const double w = frame_.w_max - (k + jitter) * dw;
      if (w <= 0) break;
      if (w >= w_start) continue;
      if (!have_g) coords(w, g);
      coords(std::max(w - dw, 0.0), gn);
      const float delta = float(std::sqrt((gn[0] - g[0]) * (gn[0] - g[0]) + (gn[1] - g[1]) * (gn[1] - g[1]) +
                                          (gn[2] - g[2]) * (gn[2] - g[2])));
      const double gc[3] = {g[0], g[1], g[2]};
      std::copy(gn, gn + 3, g);
      have_g = true;
      if (!(gc[0] >= 0 && gc[1] >= 0 && gc[2] >= 0 && gc[0] <= dims_.nu - 1 && gc[1] <= dims_.nv - 1 &&
            gc[2] <= dims_.nw - 1))
        continue;
      const int i = std::min(int(gc[0]), dims_.nu - 2), j = std::min(int(gc[1]), dims_.nv - 2),
                kk = std::min(int(gc[2]), dims_.nw - 2);
      if (occupancy && delta <= max_skip_delta_ &&
          occupancy_[size_t(i + int64_t(dims_.nu - 1) * (j + int64_t(dims_.nv - 1) * kk))] == 0)
        continue;
      const float fu = float(gc[0] - i), fv = float(gc[1] - j), fw = float(gc[2] - kk);
      float wt[8];
      trilinear_weights(fu, fv, fw, wt);
      const int64_t base = index(i, j, kk);
      const float* p = params_.data() + base * kStride;
      float raw = 0;
      for (int c = 0; c < 8; ++c) raw += wt[c] * p[corner[c]];
      const float sigma = softplusf(raw + shift_);
      const float alpha = -std::expm1(-sigma * delta);
      const float weight = T * alpha;
      if (!(weight >= s.min_weight)) continue;
      float f[3 * kShCoeffs] = {};
      for (int c = 0; c < 8; ++c) {
        const float* pc = p + corner[c] + 1;
        for (int q = 0; q < 3 * kShCoeffs; ++q) f[q] += wt[c] * pc[q];
      }
      float rgb[3];
      for (int ch = 0; ch < 3; ++ch) {
        float pre = 0;
        for (int b = 0; b < kShCoeffs; ++b) pre += sh[b] * f[3 * b + ch];
        rgb[ch] = sigmoidf(pre);
        res.rgb[ch] += weight * rgb[ch];
      }
      if (samples) {
        RaySample rs;
        rs.base = base;
        rs.fu = fu, rs.fv = fv, rs.fw = fw;
        rs.delta = delta;
        rs.alpha = alpha, rs.trans = T;
        rs.dsigma = sigmoidf(raw + shift_);
        std::copy(rgb, rgb + 3, rs.rgb);
        std::copy(sh, sh + kShCoeffs, rs.sh);
        samples->push_back(rs);
      }
      T *= 1 - alpha;
      if (T < s.min_transmittance) break;
    }
  }
  int idx[4];
  float w[4];
  env_taps(ray.direction, idx, w);
  for (int ch = 0; ch < 3; ++ch) {
    float pre = 0;
    for (int q = 0; q < 4; ++q) pre += w[q] * env_[size_t(idx[q]) * 3 + ch];
    res.env[ch] = sigmoidf(pre);
    res.rgb[ch] += T * res.env[ch];
  }
  res.trans = T;
  return res;
}

void RadianceField::march_backward(const std::vector<RaySample>& samples, const RayResult& result,
                                   const float g[3], std::vector<SampleGrad>* grads, float env_grad[3]) const {
  // C = sum_k T_k a_k c_k + T_end env. With S the colour behind sample k (later samples and env):
  // dC/da_k = T_k c_k - S / (1 - a_k) and da_k/dr = (1 - a_k) delta sigmoid(r + shift), so
  // dL/dr = delta sigmoid(r + shift) ((1 - a_k) T_k g.c_k - g.S): no division by 1 - a_k.
  float S[3];
  for (int ch = 0; ch < 3; ++ch) {
    S[ch] = result.trans * result.env[ch];
    env_grad[ch] = g[ch] * result.trans * result.env[ch] * (1 - result.env[ch]);
  }
  for (size_t n = samples.size(); n-- > 0;) {
    const RaySample& s = samples[n];
    const float weight = s.trans * s.alpha;
    SampleGrad sg;
    sg.base = s.base;
    sg.fu = s.fu, sg.fv = s.fv, sg.fw = s.fw;
    float gc = 0, gs = 0;
    for (int ch = 0; ch < 3; ++ch) {
      gc += g[ch] * s.rgb[ch];
      gs += g[ch] * S[ch];
      sg.d_pre[ch] = weight * g[ch] * s.rgb[ch] * (1 - s.rgb[ch]);
      S[ch] += weight * s.rgb[ch];
    }
    sg.d_raw = s.delta * s.dsigma * ((1 - s.alpha) * s.trans * gc - gs);
    std::copy(s.sh, s.sh + kShCoeffs, sg.sh);
    grads->push_back(sg);
  }
}

std::vector<float> RadianceField::render(const Camera& camera, const MarchSettings& s) const {
  std::vector<float> img(size_t(camera.width) * camera.height * 3);
  parallel_for(0, camera.height, [&](int64_t y) {
    for (int x = 0; x < camera.width; ++x) {
      const RayResult r = march(pixel_ray(camera, x, int(y)), 0.5f, s, nullptr);
      for (int ch = 0; ch < 3; ++ch) img[(size_t(y) * camera.width + x) * 3 + ch] = std::clamp(r.rgb[ch], 0.f, 1.f);
    }
  });
  return img;
}

void RadianceField::save(const std::string& path) const {
  const Json header{{"format", kFieldFormat},
                    {"version", kFieldVersion},
                    {"frame", frame_.to_json()},
                    {"dims", {dims_.nu, dims_.nv, dims_.nw}},
                    {"density_shift", shift_},
                    {"floats_per_point", kStoredFloats},
                    {"env", {kEnvH, kEnvW, 3}}};
  const std::string h = header.dump();
  write_file_atomic_with(path, [&](const std::string& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    f << kFieldMagic << '\n' << h << '\n';
    std::vector<float> buf(size_t(dims_.points()) * kStoredFloats);
    for (int64_t p = 0; p < dims_.points(); ++p)
      std::memcpy(&buf[size_t(p) * kStoredFloats], &params_[size_t(p) * kStride], sizeof(float) * kStoredFloats);
    f.write(reinterpret_cast<const char*>(buf.data()), std::streamsize(buf.size() * sizeof(float)));
    f.write(reinterpret_cast<const char*>(env_.data()), std::streamsize(env_.size() * sizeof(float)));
    if (!f) throw InputError(path, "could not write the radiance field");
  });
}

RadianceField RadianceField::load(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path, "missing or unreadable: not a radiance-field model (field.bin)");
  std::string magic, header;
  std::getline(f, magic);
  if (magic != kFieldMagic) throw InputError(path, "not a weathergs radiance field (bad magic)");
  std::getline(f, header);
  Json j;
  try {
    j = Json::parse(header);
  } catch (const std::exception& e) {
    throw InputError(path, std::string("corrupt header: ") + e.what());
  }
  JsonReader r(j, path);
  if (r.get<std::string>("format") != kFieldFormat) throw InputError(r.where("format"), std::string("expected ") + kFieldFormat);
  if (r.get<int>("version") != kFieldVersion)
    throw InputError(r.where("version"), "expected version " + std::to_string(kFieldVersion) + ": retrain the model");
  RadianceField out;
  out.frame_ = FrustumFrame::from_json(r.child("frame"));
  const auto dims = r.get_array<3>("dims", 2, 4096);
  out.dims_ = GridDims{int(dims[0]), int(dims[1]), int(dims[2])};
  out.shift_ = float(r.get_number("density_shift", -100, 100));
  if (r.get<int>("floats_per_point") != kStoredFloats) throw InputError(r.where("floats_per_point"), "unexpected layout");
  const auto env = r.get_array<3>("env");
  if (int(env[0]) != kEnvH || int(env[1]) != kEnvW || int(env[2]) != 3) throw InputError(r.where("env"), "unexpected size");
  r.finish();
  const float sigma_min = kOccupancyMargin * kOccupancyWeight / out.max_skip_delta_;
  out.active_raw_ = softplus_inverse(sigma_min) - out.shift_;
  std::vector<float> buf(size_t(out.dims_.points()) * kStoredFloats);
  out.env_.assign(size_t(kEnvW) * kEnvH * 3, 0.f);
  f.read(reinterpret_cast<char*>(buf.data()), std::streamsize(buf.size() * sizeof(float)));
  f.read(reinterpret_cast<char*>(out.env_.data()), std::streamsize(out.env_.size() * sizeof(float)));
  if (!f || f.peek() != std::char_traits<char>::eof())
    throw InputError(path, "truncated or oversized: expected " + std::to_string(buf.size() + out.env_.size()) +
                               " float32 values after the header");
  out.params_.assign(size_t(out.dims_.points()) * kStride, 0.f);
  for (int64_t p = 0; p < out.dims_.points(); ++p)
    std::memcpy(&out.params_[size_t(p) * kStride], &buf[size_t(p) * kStoredFloats], sizeof(float) * kStoredFloats);
  for (float v : out.params_)
    if (!std::isfinite(v)) throw InputError(path, "holds non-finite values");
  out.rebuild_occupancy();
  return out;
}

}  // namespace weathergs::nerf
