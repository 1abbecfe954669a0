// Per-Gaussian math of 3D Gaussian Splatting (Kerbl et al. 2023, graphdeco-inria
// diff-gaussian-rasterization), each forward function with its hand-written vector-Jacobian product
// (`*_vjp`), templated on the scalar so the finite-difference tests run the same code in double.
//
// Conventions: quaternions are (w, x, y, z); covariances are symmetric and their gradients are given
// as symmetric matrices (an off-diagonal entry carries half of the derivative with respect to the
// shared value); pixel coordinates follow core/camera.h (pixel (i, j) has its center at i+0.5, j+0.5).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace weathergs::reconstruction {

template <typename T> using Vec2 = Eigen::Matrix<T, 2, 1>;
template <typename T> using Vec3 = Eigen::Matrix<T, 3, 1>;
template <typename T> using Vec4 = Eigen::Matrix<T, 4, 1>;
template <typename T> using Mat2 = Eigen::Matrix<T, 2, 2>;
template <typename T> using Mat3 = Eigen::Matrix<T, 3, 3>;
template <typename T> using Mat23 = Eigen::Matrix<T, 2, 3>;

constexpr int kMaxShDegree = 3;
constexpr int kShCoeffs = 16;              // (kMaxShDegree + 1)^2
constexpr int kShFloats = kShCoeffs * 3;   // RGB per coefficient

// Reference rasterizer constants (diff-gaussian-rasterization, forward.cu / auxiliary.h).
constexpr double kNearPlane = 0.2;          // cull p_camera.z <= 0.2
constexpr double kJacobianClampFov = 1.3;   // clamp x/z to 1.3 x the half field of view
constexpr double kLowPass2d = 0.3;          // px^2 added to the 2D covariance diagonal (RasterCamera::low_pass)
constexpr double kMinEigenGap = 0.1;        // sqrt(max(0.1, mid^2 - det)) in the radius
constexpr double kAlphaMax = 0.99;
constexpr double kAlphaMin = 1.0 / 255.0;
constexpr double kTransmittanceMin = 1e-4;
// The reference bins Gaussians into 16x16 tiles and clips each to the tiles of its 3-sigma
// rectangle (getRect): which pixels a Gaussian may reach depends on that grid, so the images do.
// We keep that grid for the clipping (kReferenceTile) and bin into 32x32 tiles (kTileSize): a
// Gaussian's pixels are the same, its tile entries ~40 % fewer (benchmarks/README.md).
constexpr int kReferenceTile = 16;
constexpr int kTileSize = 32;
// Below this quaternion norm the rotation is taken as identity with zero gradient (torch.normalize
// would divide by max(norm, 1e-12) and produce gradients of 1e12).
constexpr double kMinQuatNorm = 1e-12;

// Spherical-harmonics constants of the reference (sh_utils.py / forward.cu).
constexpr double kShC0 = 0.28209479177387814;
constexpr double kShC1 = 0.4886025119029199;
constexpr double kShC2[5] = {1.0925484305920792, -1.0925484305920792, 0.31539156525252005,
                             -1.0925484305920792, 0.5462742152960396};
constexpr double kShC3[7] = {-0.5900435899266435, 2.890611442640554, -0.4570457994644658,
                             0.3731763325901154,  -0.4570457994644658, 1.445305721320277,
                             -0.5900435899266435};

// exp and log of the per-Gaussian math in float, written with plain float operations (no libm, no
// fused multiply-add) so that the SIMD preprocessing (preprocess_simd.cc) does the same operations
// lane by lane in vector registers; libm's expf and logf are one call per lane (48 calls per 8
// Gaussians took ~20 % of the preprocessing, benchmarks/README.md). exp: Cephes' expf (reduction
// x = n ln 2 + r with ln 2 split in two, e^r = 1 + r + r^2 p(r), p of degree 5), x clamped to
// [-87, 88] so that 2^n is a normal float; log: Cephes' logf (mantissa in [sqrt(1/2), sqrt(2)),
// degree-8 polynomial), for positive normal x. Both within 2 ulp of the exact values (test
// GaussianMathTest.FloatExpAndLogAreAccurate); a NaN gives NaN. double: std::exp and std::log (the
// finite-difference tests).
inline float model_exp(float x) {
  if (x != x) return x;
  x = std::min(std::max(x, -87.0f), 88.0f);
  const float t = x * 1.44269504088896341f + 0.5f;
  int n = int(t);  // floor(t): truncation, one less where that rounded up (t < 0)
  n -= float(n) > t ? 1 : 0;
  const float z = float(n);
  const float r = (x - z * 0.693359375f) - z * -2.12194440e-4f;
  const float r2 = r * r;
  float p = 1.9875691500e-4f;
  for (float c : {1.3981999507e-3f, 8.3334519073e-3f, 4.1665795894e-2f, 1.6666665459e-1f, 5.0000001201e-1f}) p = p * r + c;
  const float e_r = (p * r2 + r) + 1.0f;
  const int32_t bits = (n + 127) << 23;
  float scale;
  std::memcpy(&scale, &bits, 4);
  return e_r * scale;
}
inline double model_exp(double x) { return std::exp(x); }

inline float model_log(float x) {
  int32_t bits;
  std::memcpy(&bits, &x, 4);
  int e = ((bits >> 23) & 0xff) - 126;  // x = m 2^e, m in [0.5, 1)
  const int32_t m_bits = (bits & 0x007fffff) | 0x3f000000;
  float m;
  std::memcpy(&m, &m_bits, 4);
  const bool low = m < 0.707106781186547524f;
  e -= low ? 1 : 0;
  const float f = low ? (m + m) - 1.0f : m - 1.0f;
  const float f2 = f * f;
  float p = 7.0376836292e-2f;
  for (float c : {-1.1514610310e-1f, 1.1676998740e-1f, -1.2420140846e-1f, 1.4249322787e-1f, -1.6668057665e-1f,
                  2.0000714765e-1f, -2.4999993993e-1f, 3.3333331174e-1f})
    p = p * f + c;
  const float fe = float(e);
  float y = ((p * f) * f2 + fe * -2.12194440e-4f) + -0.5f * f2;
  return (f + y) + fe * 0.693359375f;
}
inline double model_log(double x) { return std::log(x); }

template <typename T>
inline T sigmoid(T x) {
  // Two branches so that exp never overflows for logits of either sign.
  if (x >= T(0)) return T(1) / (T(1) + model_exp(-x));
  T e = model_exp(x);
  return e / (T(1) + e);
}

// ---- Rotation from an unnormalized quaternion ----
template <typename T>
inline Mat3<T> quat_to_rotmat(const Vec4<T>& q_raw) {
  T n = q_raw.norm();
  if (!(n >= T(kMinQuatNorm))) return Mat3<T>::Identity();
  Vec4<T> q = q_raw / n;
  T w = q[0], x = q[1], y = q[2], z = q[3];
  Mat3<T> r;
  r << T(1) - T(2) * (y * y + z * z), T(2) * (x * y - w * z), T(2) * (x * z + w * y),
      T(2) * (x * y + w * z), T(1) - T(2) * (x * x + z * z), T(2) * (y * z - w * x),
      T(2) * (x * z - w * y), T(2) * (y * z + w * x), T(1) - T(2) * (x * x + y * y);
  return r;
}

template <typename T>
inline Vec4<T> quat_to_rotmat_vjp(const Vec4<T>& q_raw, const Mat3<T>& v_r) {
  T n = q_raw.norm();
  if (!(n >= T(kMinQuatNorm))) return Vec4<T>::Zero();
  Vec4<T> q = q_raw / n;
  T w = q[0], x = q[1], y = q[2], z = q[3];
  const Mat3<T>& g = v_r;
  Vec4<T> v_q;
  v_q[0] = T(2) * (-z * g(0, 1) + y * g(0, 2) + z * g(1, 0) - x * g(1, 2) - y * g(2, 0) + x * g(2, 1));
  v_q[1] = T(2) * (y * g(0, 1) + z * g(0, 2) + y * g(1, 0) - T(2) * x * g(1, 1) - w * g(1, 2) +
                   z * g(2, 0) + w * g(2, 1) - T(2) * x * g(2, 2));
  v_q[2] = T(2) * (-T(2) * y * g(0, 0) + x * g(0, 1) + w * g(0, 2) + x * g(1, 0) + z * g(1, 2) -
                   w * g(2, 0) + z * g(2, 1) - T(2) * y * g(2, 2));
  v_q[3] = T(2) * (-T(2) * z * g(0, 0) - w * g(0, 1) + x * g(0, 2) + w * g(1, 0) -
                   T(2) * z * g(1, 1) + y * g(1, 2) + x * g(2, 0) + y * g(2, 1));
  // Through the normalization q = q_raw / |q_raw|.
  return (v_q - q * q.dot(v_q)) / n;
}

// ---- 3D covariance Sigma = R diag(s^2) R^T with s = exp(log_scale) ----
template <typename T>
inline Vec3<T> scale_from_log(const Vec3<T>& log_scale) {
  return Vec3<T>(model_exp(log_scale[0]), model_exp(log_scale[1]), model_exp(log_scale[2]));
}

// From the scales s = scale_from_log(log_scale) (the rasterizer keeps them from its forward pass).
template <typename T>
inline Mat3<T> covariance_3d_from_scale(const Vec3<T>& s, const Vec4<T>& q) {
  Mat3<T> m = quat_to_rotmat(q) * s.asDiagonal();
  return m * m.transpose();
}

template <typename T>
inline Mat3<T> covariance_3d(const Vec3<T>& log_scale, const Vec4<T>& q) {
  return covariance_3d_from_scale(scale_from_log(log_scale), q);
}

// v_sigma: symmetric gradient. Adds into v_log_scale and v_q. s = scale_from_log(log_scale).
template <typename T>
inline void covariance_3d_vjp_from_scale(const Vec3<T>& s, const Vec4<T>& q, const Mat3<T>& v_sigma,
                                         Vec3<T>* v_log_scale, Vec4<T>* v_q) {
  Mat3<T> r = quat_to_rotmat(q);
  Mat3<T> m = r * s.asDiagonal();
  Mat3<T> v_m = (v_sigma + v_sigma.transpose()) * m;  // d(M M^T) with a symmetric gradient
  Mat3<T> v_r = v_m * s.asDiagonal();
  for (int j = 0; j < 3; ++j) (*v_log_scale)[j] += v_m.col(j).dot(r.col(j)) * s[j];
  *v_q += quat_to_rotmat_vjp(q, v_r);
}

template <typename T>
inline void covariance_3d_vjp(const Vec3<T>& log_scale, const Vec4<T>& q, const Mat3<T>& v_sigma,
                              Vec3<T>* v_log_scale, Vec4<T>* v_q) {
  covariance_3d_vjp_from_scale(scale_from_log(log_scale), q, v_sigma, v_log_scale, v_q);
}

// ---- Camera as the rasterizer sees it ----
template <typename T>
struct RasterCamera {
  int width = 0, height = 0;
  T fx = 0, fy = 0, cx = 0, cy = 0;
  Mat3<T> rotation = Mat3<T>::Identity();  // camera_from_world rotation
  Vec3<T> translation = Vec3<T>::Zero();   // camera_from_world translation
  Vec3<T> center_world = Vec3<T>::Zero();
  // Jacobian clamp on x/z and y/z: the image's extent widened by 30% of the half size on each side
  // (equals the reference's +-1.3 tan(fov/2) when the principal point is centered).
  T lim_x_lo = 0, lim_x_hi = 0, lim_y_lo = 0, lim_y_hi = 0;
  // px^2 added to the 2D covariance diagonal: the reference's 0.3 for a full-resolution pixel. An
  // image downsampled by f takes 0.3 / f^2 (reconstruction/resolution.h), the same footprint in the
  // scene, so a model trained on small images renders at full size as it was trained.
  T low_pass = T(kLowPass2d);

  template <typename CameraT>
  static RasterCamera from(const CameraT& c) {
    RasterCamera r;
    r.width = c.width;
    r.height = c.height;
    r.fx = T(c.fx); r.fy = T(c.fy); r.cx = T(c.cx); r.cy = T(c.cy);
    r.rotation = c.rotation().template cast<T>();
    r.translation = c.translation().template cast<T>();
    r.center_world = c.center_world().template cast<T>();
    const double ex = (kJacobianClampFov - 1.0) * 0.5 * c.width, ey = (kJacobianClampFov - 1.0) * 0.5 * c.height;
    r.lim_x_lo = T(-(c.cx + ex) / c.fx);
    r.lim_x_hi = T((c.width - c.cx + ex) / c.fx);
    r.lim_y_lo = T(-(c.cy + ey) / c.fy);
    r.lim_y_hi = T((c.height - c.cy + ey) / c.fy);
    return r;
  }
};

// ---- EWA projection: mean and 2D covariance (low-pass included) of a Gaussian in pixels ----
template <typename T>
struct Projection {
  Vec3<T> p_camera;
  Vec2<T> mean;  // pixel coordinates
  Mat2<T> cov;   // 2D covariance in px^2, with the 0.3 px^2 low-pass
};

// The caller checks p_camera.z > kNearPlane first (the function assumes it).
template <typename T>
inline Projection<T> project_gaussian(const Vec3<T>& p_world, const Mat3<T>& sigma, const RasterCamera<T>& cam) {
  Projection<T> out;
  const Vec3<T>& p = out.p_camera = cam.rotation * p_world + cam.translation;
  const T z = p.z(), iz = T(1) / z;
  out.mean = Vec2<T>(cam.fx * p.x() * iz + cam.cx, cam.fy * p.y() * iz + cam.cy);
  const T tx = std::clamp(p.x() * iz, cam.lim_x_lo, cam.lim_x_hi) * z;
  const T ty = std::clamp(p.y() * iz, cam.lim_y_lo, cam.lim_y_hi) * z;
  Mat23<T> j;
  j << cam.fx * iz, T(0), -cam.fx * tx * iz * iz, T(0), cam.fy * iz, -cam.fy * ty * iz * iz;
  Mat23<T> t = j * cam.rotation;
  out.cov = t * sigma * t.transpose();
  out.cov(0, 0) += cam.low_pass;
  out.cov(1, 1) += cam.low_pass;
  return out;
}

// v_cov: symmetric gradient of the 2D covariance. Adds into v_p_world and v_sigma. The clamp of x/z
// is differentiated exactly (the reference drops the dependence of the clamped x on z).
template <typename T>
inline void project_gaussian_vjp(const Vec3<T>& p_world, const Mat3<T>& sigma, const RasterCamera<T>& cam,
                                 const Vec2<T>& v_mean, const Mat2<T>& v_cov, Vec3<T>* v_p_world,
                                 Mat3<T>* v_sigma) {
  const Vec3<T> p = cam.rotation * p_world + cam.translation;
  const T z = p.z(), iz = T(1) / z;
  const T rx = p.x() * iz, ry = p.y() * iz;
  const bool clamp_x = rx < cam.lim_x_lo || rx > cam.lim_x_hi;
  const bool clamp_y = ry < cam.lim_y_lo || ry > cam.lim_y_hi;
  const T tx = std::clamp(rx, cam.lim_x_lo, cam.lim_x_hi) * z;
  const T ty = std::clamp(ry, cam.lim_y_lo, cam.lim_y_hi) * z;
  Mat23<T> j;
  j << cam.fx * iz, T(0), -cam.fx * tx * iz * iz, T(0), cam.fy * iz, -cam.fy * ty * iz * iz;
  const Mat23<T> t = j * cam.rotation;
  const Mat2<T> vc = T(0.5) * (v_cov + v_cov.transpose());
  *v_sigma += t.transpose() * vc * t;
  const Mat23<T> v_t = T(2) * vc * t * sigma;
  const Mat23<T> v_j = v_t * cam.rotation.transpose();
  // J00 = fx/z, J02 = -fx tx/z^2, J11 = fy/z, J12 = -fy ty/z^2.
  Vec3<T> v_p(0, 0, 0);
  const T v_tx = -cam.fx * iz * iz * v_j(0, 2);
  const T v_ty = -cam.fy * iz * iz * v_j(1, 2);
  T v_z = -cam.fx * iz * iz * v_j(0, 0) - cam.fy * iz * iz * v_j(1, 1) +
          T(2) * cam.fx * tx * iz * iz * iz * v_j(0, 2) + T(2) * cam.fy * ty * iz * iz * iz * v_j(1, 2);
  // tx = x when not clamped, lim * z when clamped.
  if (clamp_x) v_z += v_tx * (tx * iz); else v_p.x() += v_tx;
  if (clamp_y) v_z += v_ty * (ty * iz); else v_p.y() += v_ty;
  // Mean: u = fx x/z + cx, v = fy y/z + cy.
  v_p.x() += cam.fx * iz * v_mean.x();
  v_p.y() += cam.fy * iz * v_mean.y();
  v_z += -cam.fx * p.x() * iz * iz * v_mean.x() - cam.fy * p.y() * iz * iz * v_mean.y();
  v_p.z() += v_z;
  *v_p_world += cam.rotation.transpose() * v_p;
}

// ---- Conic (inverse 2D covariance) stored as (a, b, c) for [[a, b], [b, c]] ----
// v_conic holds dL/da, dL/db, dL/dc where b is the single off-diagonal value; returns the symmetric
// gradient of the covariance.
template <typename T>
inline Mat2<T> inverse_2x2_vjp(const Mat2<T>& cov, const Vec3<T>& v_conic) {
  const T det = cov(0, 0) * cov(1, 1) - cov(0, 1) * cov(0, 1);
  Mat2<T> inv;
  inv << cov(1, 1) / det, -cov(0, 1) / det, -cov(0, 1) / det, cov(0, 0) / det;
  Mat2<T> g;
  g << v_conic[0], T(0.5) * v_conic[1], T(0.5) * v_conic[1], v_conic[2];
  return -inv * g * inv;
}

// ---- Spherical harmonics colour (degree <= 3), +0.5 offset and clamp at 0 as the reference ----
template <typename T>
inline void sh_basis(int degree, const Vec3<T>& d, T* b) {
  const T x = d.x(), y = d.y(), z = d.z();
  b[0] = T(kShC0);
  if (degree < 1) return;
  b[1] = -T(kShC1) * y;
  b[2] = T(kShC1) * z;
  b[3] = -T(kShC1) * x;
  if (degree < 2) return;
  const T xx = x * x, yy = y * y, zz = z * z;
  b[4] = T(kShC2[0]) * x * y;
  b[5] = T(kShC2[1]) * y * z;
  b[6] = T(kShC2[2]) * (T(2) * zz - xx - yy);
  b[7] = T(kShC2[3]) * x * z;
  b[8] = T(kShC2[4]) * (xx - yy);
  if (degree < 3) return;
  b[9] = T(kShC3[0]) * y * (T(3) * xx - yy);
  b[10] = T(kShC3[1]) * x * y * z;
  b[11] = T(kShC3[2]) * y * (T(4) * zz - xx - yy);
  b[12] = T(kShC3[3]) * z * (T(2) * zz - T(3) * xx - T(3) * yy);
  b[13] = T(kShC3[4]) * x * (T(4) * zz - xx - yy);
  b[14] = T(kShC3[5]) * z * (xx - yy);
  b[15] = T(kShC3[6]) * x * (xx - T(3) * yy);
}

// Derivatives of the basis with respect to the (unnormalized-treated) direction components.
template <typename T>
inline void sh_basis_grad(int degree, const Vec3<T>& d, T* bx, T* by, T* bz) {
  const T x = d.x(), y = d.y(), z = d.z();
  const int n = (degree + 1) * (degree + 1);
  for (int k = 0; k < n; ++k) bx[k] = by[k] = bz[k] = T(0);
  if (degree < 1) return;
  by[1] = -T(kShC1);
  bz[2] = T(kShC1);
  bx[3] = -T(kShC1);
  if (degree < 2) return;
  const T xx = x * x, yy = y * y, zz = z * z;
  bx[4] = T(kShC2[0]) * y;  by[4] = T(kShC2[0]) * x;
  by[5] = T(kShC2[1]) * z;  bz[5] = T(kShC2[1]) * y;
  bx[6] = -T(2) * T(kShC2[2]) * x;  by[6] = -T(2) * T(kShC2[2]) * y;  bz[6] = T(4) * T(kShC2[2]) * z;
  bx[7] = T(kShC2[3]) * z;  bz[7] = T(kShC2[3]) * x;
  bx[8] = T(2) * T(kShC2[4]) * x;  by[8] = -T(2) * T(kShC2[4]) * y;
  if (degree < 3) return;
  bx[9] = T(kShC3[0]) * T(6) * x * y;  by[9] = T(kShC3[0]) * (T(3) * xx - T(3) * yy);
  bx[10] = T(kShC3[1]) * y * z;  by[10] = T(kShC3[1]) * x * z;  bz[10] = T(kShC3[1]) * x * y;
  bx[11] = -T(kShC3[2]) * T(2) * x * y;  by[11] = T(kShC3[2]) * (T(4) * zz - xx - T(3) * yy);
  bz[11] = T(kShC3[2]) * T(8) * y * z;
  bx[12] = -T(kShC3[3]) * T(6) * x * z;  by[12] = -T(kShC3[3]) * T(6) * y * z;
  bz[12] = T(kShC3[3]) * (T(6) * zz - T(3) * xx - T(3) * yy);
  bx[13] = T(kShC3[4]) * (T(4) * zz - T(3) * xx - yy);  by[13] = -T(kShC3[4]) * T(2) * x * y;
  bz[13] = T(kShC3[4]) * T(8) * x * z;
  bx[14] = T(kShC3[5]) * T(2) * x * z;  by[14] = -T(kShC3[5]) * T(2) * y * z;  bz[14] = T(kShC3[5]) * (xx - yy);
  bx[15] = T(kShC3[6]) * (T(3) * xx - T(3) * yy);  by[15] = -T(kShC3[6]) * T(6) * x * y;
}

// Unit view direction from the camera center to the Gaussian; zero when they coincide.
template <typename T>
inline Vec3<T> view_direction(const Vec3<T>& p_world, const Vec3<T>& cam_center, T* length) {
  Vec3<T> v = p_world - cam_center;
  *length = v.norm();
  return *length > T(0) ? Vec3<T>(v / *length) : Vec3<T>(T(0), T(0), T(0));
}

// Colour = max(0, sum_k b_k sh_k + 0.5); clamped[c] records the channels cut at 0.
template <typename T>
inline Vec3<T> sh_to_color(int degree, const T* sh, const Vec3<T>& dir, bool clamped[3]) {
  T b[kShCoeffs];
  sh_basis(degree, dir, b);
  const int n = (degree + 1) * (degree + 1);
  Vec3<T> c(T(0.5), T(0.5), T(0.5));
  for (int k = 0; k < n; ++k)
    for (int ch = 0; ch < 3; ++ch) c[ch] += b[k] * sh[k * 3 + ch];
  for (int ch = 0; ch < 3; ++ch) {
    clamped[ch] = c[ch] < T(0);
    if (clamped[ch]) c[ch] = T(0);
  }
  return c;
}

// Adds into v_sh (same layout as sh) and v_p_world (through the view direction).
template <typename T>
inline void sh_to_color_vjp(int degree, const T* sh, const Vec3<T>& p_world, const Vec3<T>& cam_center,
                            const Vec3<T>& v_color_in, const bool clamped[3], T* v_sh, Vec3<T>* v_p_world) {
  T len;
  const Vec3<T> dir = view_direction(p_world, cam_center, &len);
  Vec3<T> v_color = v_color_in;
  for (int ch = 0; ch < 3; ++ch)
    if (clamped[ch]) v_color[ch] = T(0);
  T b[kShCoeffs];
  sh_basis(degree, dir, b);
  const int n = (degree + 1) * (degree + 1);
  for (int k = 0; k < n; ++k)
    for (int ch = 0; ch < 3; ++ch) v_sh[k * 3 + ch] += b[k] * v_color[ch];
  if (degree < 1 || !(len > T(0))) return;
  T bx[kShCoeffs], by[kShCoeffs], bz[kShCoeffs];
  sh_basis_grad(degree, dir, bx, by, bz);
  Vec3<T> v_dir(0, 0, 0);
  for (int k = 1; k < n; ++k) {
    const T s = sh[k * 3] * v_color[0] + sh[k * 3 + 1] * v_color[1] + sh[k * 3 + 2] * v_color[2];
    v_dir += s * Vec3<T>(bx[k], by[k], bz[k]);
  }
  *v_p_world += (v_dir - dir * dir.dot(v_dir)) / len;
}

}  // namespace weathergs::reconstruction
