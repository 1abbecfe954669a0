// An explicit-grid radiance field in the DVGO / Plenoxels family (docs/nerf.md): values on the lattice
// points of the frustum grid of frustum.h, trilinearly interpolated, volume-rendered along each ray.
// Per lattice point: a raw density r (post-activated after interpolation as in DVGO:
// sigma = softplus(r + shift)) and degree-1 spherical-harmonics colour (4 coefficients per channel,
// colour = sigmoid(sum_b Y_b(d) k_b)). Light that passes through the grid takes the colour of a small
// learned environment map (latitude-longitude in the reference frame): the sides of other views.
//
// Rendering a ray: samples at equal steps of disparity w (`samples_per_cell` per grid cell along w),
// jittered during training; the opacity of a sample is alpha = 1 - exp(-sigma * delta) with delta the
// distance to the next sample in grid cells. Samples whose weight T*alpha is below `min_weight` are
// skipped entirely (DVGO's fast_color_thres: neither colour nor transmittance), the march stops when
// the transmittance falls below `min_transmittance`. Empty-space skipping by the occupancy of each
// cell is exact: a cell is skipped only when no corner could give a sample weight >= min_weight.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/camera.h"
#include "nerf/frustum.h"

namespace weathergs::nerf {

// Floats per lattice point: [0] raw density, [1 + 3 b + ch] SH coefficient b of channel ch, 3 pad
// (one 64-byte line per point: a trilinear lookup touches 8 lines).
constexpr int kStride = 16;
constexpr int kShCoeffs = 4;
constexpr int kEnvW = 32, kEnvH = 16;

struct GridDims {
  int nu = 2, nv = 2, nw = 2;  // lattice points per axis (>= 2); cells = n - 1
  int64_t points() const { return int64_t(nu) * nv * nw; }
  int64_t cells() const { return int64_t(nu - 1) * (nv - 1) * (nw - 1); }
  bool operator==(const GridDims& o) const { return nu == o.nu && nv == o.nv && nw == o.nw; }
};

struct MarchSettings {
  int samples_per_cell = 2;         // along w
  float min_weight = 1e-4f;         // skip samples with T * alpha below this (DVGO's fast_color_thres)
  float min_transmittance = 1e-4f;  // stop the march below this
  bool use_occupancy = true;        // exact empty-space skipping (off only to test that it is exact)
};

struct Ray {
  Eigen::Vector3d origin, direction;  // world; direction unit length
};

// One sample that contributed to a ray (what the backward pass needs).
struct RaySample {
  int64_t base;        // lattice index of the cell's lowest corner
  float fu, fv, fw;    // trilinear fractions in the cell
  float delta;         // step to the next sample, grid cells
  float alpha, trans;  // opacity and the transmittance before it
  float dsigma;        // d sigma / d r = sigmoid(r + shift)
  float rgb[3];
  float sh[kShCoeffs];  // basis values Y_b(d)
};

struct RayResult {
  std::array<float, 3> rgb{};
  float trans = 1;  // transmittance left for the environment
  float env[3]{};   // environment colour behind the ray
};

// The gradient of one sample: d loss / d r and d loss / d (pre-sigmoid colour), with what is needed
// to spread them over the 8 corners.
struct SampleGrad {
  int64_t base;
  float fu, fv, fw;
  float d_raw;
  float d_pre[3];
  float sh[kShCoeffs];
};

class RadianceField {
 public:
  RadianceField() = default;
  // A fresh field: raw density 0 (alpha = alpha_init per grid cell of path), grey colour.
  RadianceField(const FrustumFrame& frame, const GridDims& dims, double alpha_init);

  const FrustumFrame& frame() const { return frame_; }
  const GridDims& dims() const { return dims_; }
  float density_shift() const { return shift_; }
  std::vector<float>& params() { return params_; }
  const std::vector<float>& params() const { return params_; }
  std::vector<float>& env() { return env_; }  // kEnvH x kEnvW x 3 pre-sigmoid colours
  const std::vector<float>& env() const { return env_; }

  // Lattice index and the point's continuous grid coordinates.
  int64_t index(int i, int j, int k) const { return i + int64_t(dims_.nu) * (j + int64_t(dims_.nv) * k); }
  Eigen::Vector3d grid_coords(const Eigen::Vector3d& p_world) const;

  // Occupancy: per cell the number of corners whose raw density reaches active_raw(); a cell with
  // none is skipped (exact, see the header comment). rebuild_occupancy() after editing params();
  // update_occupancy(p, was, is) after changing one point's activity.
  float active_raw() const { return active_raw_; }
  void rebuild_occupancy();
  void update_occupancy(int64_t point, bool was_active, bool is_active);
  int64_t occupied_cells() const;

  // The same field on a finer or coarser lattice (trilinear resampling of every value).
  RadianceField resampled(const GridDims& dims) const;

  // Renders one ray. `samples` (may be null) receives the contributing samples in order.
  RayResult march(const Ray& ray, float jitter, const MarchSettings& s, std::vector<RaySample>* samples) const;
  // Backward of march: d loss / d rgb = `grad_rgb`; appends one SampleGrad per contributing sample
  // and returns d loss / d (environment colour) in env_grad (pre-sigmoid, before the bilinear split).
  void march_backward(const std::vector<RaySample>& samples, const RayResult& result, const float grad_rgb[3],
                      std::vector<SampleGrad>* grads, float env_grad[3]) const;
  // Bilinear environment lookup for a world direction: the 4 texels and weights.
  void env_taps(const Eigen::Vector3d& direction, int idx[4], float w[4]) const;

  // Whole image of a camera (no jitter), row-parallel, sRGB in [0, 1], H x W x 3.
  std::vector<float> render(const Camera& camera, const MarchSettings& s) const;

  // field.bin: a small JSON header (format, version, frame, dims, shift) then float32 params and env.
  void save(const std::string& path) const;  // atomic
  static RadianceField load(const std::string& path);  // InputError naming the file

 private:
  float raw_at(const RaySample& s) const;
  FrustumFrame frame_;
  GridDims dims_;
  float shift_ = 0, active_raw_ = 0, max_skip_delta_ = 4;
  std::vector<float> params_, env_;
  std::vector<uint8_t> occupancy_;  // per cell: active corners (0..8)
};

// Adds one sample's gradient to the 8 corners of its cell in `grad` (kStride floats per lattice
// point), only the corners whose w index lies in [k_lo, k_hi) (a slab; the whole lattice: 0, nw),
// and marks them in `touched`.
void spread_sample_grad(const SampleGrad& sg, const GridDims& dims, int k_lo, int k_hi, float* grad, uint8_t* touched);

// A camera's ray through pixel centre (x + 0.5, y + 0.5).
Ray pixel_ray(const Camera& camera, int x, int y);
inline float sigmoidf(float x) { return 1.f / (1.f + std::exp(-x)); }
float softplusf(float x);

}  // namespace weathergs::nerf
