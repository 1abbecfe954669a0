// The float preprocessing of the rasterizer (projection, 2D covariance, SH colour), 4 or 8 Gaussians
// at a time with GCC/Clang vector extensions, at the tile kernels' width (raster_internal.h).
//
// Same bits as the scalar template (preprocess in rasterizer.cc, which Eigen evaluates): every lane
// does that template's IEEE operations in its order. Eigen sums a fixed-size product's three terms
// as a0 + (a1 + a2) and a Vector4f's squared norm as (q0^2 + q2^2) + (q1^2 + q3^2) (its SSE
// reduction); the formulas below spell those orders out, with the Jacobian's structural zeros kept
// (0 * R(k, j) may be -0, which decides the sign of a zero sum). exp and log are model_exp and
// model_log (gaussian_math.h), their operations in vector registers (exp_v, log_v). The library
// compiles with -ffp-contract=off (no fused multiply-add). Test
// RasterizerTest.SimdPreprocessEqualsScalar compares every output.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/parallel.h"
#include "reconstruction/raster_internal.h"
#include "reconstruction/simd_lanes.h"

namespace weathergs::reconstruction::internal {

namespace {

template <typename V, typename F>
WGS_ALWAYS_INLINE V lanewise(V v, F fn) {
  for (int l = 0; l < int(sizeof(V) / sizeof(float)); ++l) v[l] = fn(v[l]);
  return v;
}

// a0 * b0 + (a1 * b1 + a2 * b2): Eigen's order for a fixed-size product's coefficient.
template <typename A, typename B, typename C, typename D, typename E, typename F>
WGS_ALWAYS_INLINE auto sum3(A a0, B b0, C a1, D b1, E a2, F b2) {
  return a0 * b0 + (a1 * b1 + a2 * b2);
}

template <typename V>
WGS_ALWAYS_INLINE V load_v(const float* p) {
  V v;
  std::memcpy(&v, p, sizeof(V));
  return v;
}

// In-place transpose of a W x W block held as W vectors (rows[l][c] becomes rows[c][l]).
template <int W>
WGS_ALWAYS_INLINE void transpose(typename Lanes<W>::f* r) {
  using vf = typename Lanes<W>::f;
  if constexpr (W == 4) {
    const vf t0 = __builtin_shufflevector(r[0], r[1], 0, 4, 1, 5), t1 = __builtin_shufflevector(r[0], r[1], 2, 6, 3, 7);
    const vf t2 = __builtin_shufflevector(r[2], r[3], 0, 4, 1, 5), t3 = __builtin_shufflevector(r[2], r[3], 2, 6, 3, 7);
    r[0] = __builtin_shufflevector(t0, t2, 0, 1, 4, 5);
    r[1] = __builtin_shufflevector(t0, t2, 2, 3, 6, 7);
    r[2] = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
    r[3] = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
  } else {
    static_assert(W == 8);
    vf t[8], u[8];
    for (int k = 0; k < 8; k += 2) {  // pairs of rows interleaved within each 128-bit half
      t[k] = __builtin_shufflevector(r[k], r[k + 1], 0, 8, 1, 9, 4, 12, 5, 13);
      t[k + 1] = __builtin_shufflevector(r[k], r[k + 1], 2, 10, 3, 11, 6, 14, 7, 15);
    }
    for (int k = 0; k < 8; k += 4)  // quads of rows: columns c and c + 4 of four rows
      for (int h = 0; h < 2; ++h) {
        u[k + 2 * h] = __builtin_shufflevector(t[k + h], t[k + h + 2], 0, 1, 8, 9, 4, 5, 12, 13);
        u[k + 2 * h + 1] = __builtin_shufflevector(t[k + h], t[k + h + 2], 2, 3, 10, 11, 6, 7, 14, 15);
      }
    for (int c = 0; c < 4; ++c) {  // the two 128-bit halves: columns c and c + 4 of all eight rows
      r[c] = __builtin_shufflevector(u[c], u[c + 4], 0, 1, 2, 3, 8, 9, 10, 11);
      r[c + 4] = __builtin_shufflevector(u[c], u[c + 4], 4, 5, 6, 7, 12, 13, 14, 15);
    }
  }
}

// model_exp (gaussian_math.h), lane by lane the same operations.
template <int W>
WGS_ALWAYS_INLINE typename Lanes<W>::f exp_v(typename Lanes<W>::f x) {
  using vf = typename Lanes<W>::f;
  using vi = typename Lanes<W>::i;
  const vi nan = x != x;
  const vf lo = vf{} - 87.0f, hi = vf{} + 88.0f;
  const vf c = x < lo ? lo : (hi < x ? hi : x);  // std::min(std::max(x, -87), 88) for a non-NaN x
  const vf t = c * 1.44269504088896341f + 0.5f;
  vi n = __builtin_convertvector(nan ? vf{} : t, vi);
  n += __builtin_convertvector(n, vf) > t;  // -1 where truncation rounded up
  const vf z = __builtin_convertvector(n, vf);
  const vf r = (c - z * 0.693359375f) - z * -2.12194440e-4f;
  const vf r2 = r * r;
  vf p = vf{} + 1.9875691500e-4f;
  for (float k : {1.3981999507e-3f, 8.3334519073e-3f, 4.1665795894e-2f, 1.6666665459e-1f, 5.0000001201e-1f})
    p = p * r + k;
  const vf e_r = (p * r2 + r) + 1.0f;
  const vi bits = (n + 127) << 23;
  vf scale;
  std::memcpy(&scale, &bits, sizeof(vf));
  return nan ? x : e_r * scale;
}

// model_log (gaussian_math.h), lane by lane the same operations.
template <int W>
WGS_ALWAYS_INLINE typename Lanes<W>::f log_v(typename Lanes<W>::f x) {
  using vf = typename Lanes<W>::f;
  using vi = typename Lanes<W>::i;
  vi bits;
  std::memcpy(&bits, &x, sizeof(vf));
  vi e = ((bits >> 23) & 0xff) - 126;
  const vi m_bits = (bits & 0x007fffff) | 0x3f000000;
  vf m;
  std::memcpy(&m, &m_bits, sizeof(vf));
  const vi low = m < 0.707106781186547524f;
  e += low;  // -1 where low
  const vf f = low ? (m + m) - 1.0f : m - 1.0f;
  const vf f2 = f * f;
  vf p = vf{} + 7.0376836292e-2f;
  for (float k : {-1.1514610310e-1f, 1.1676998740e-1f, -1.2420140846e-1f, 1.4249322787e-1f, -1.6668057665e-1f,
                  2.0000714765e-1f, -2.4999993993e-1f, 3.3333331174e-1f})
    p = p * f + k;
  const vf fe = __builtin_convertvector(e, vf);
  const vf y = ((p * f) * f2 + fe * -2.12194440e-4f) + -0.5f * f2;
  return (f + y) + fe * 0.693359375f;
}

// tile_floor_index, lane by lane.
template <int W>
WGS_ALWAYS_INLINE typename Lanes<W>::i tile_floor_v(typename Lanes<W>::f v, int grid) {
  using vf = typename Lanes<W>::f;
  using vi = typename Lanes<W>::i;
  const vf t = v / float(kReferenceTile);
  const vf hi = vf{} + float(grid);
  const vf c = t < 0.0f ? vf{} : (hi < t ? hi : t);  // std::clamp(t, 0, grid)
  const vi n = __builtin_convertvector(c == c ? c : vf{}, vi);
  return n;
}

// finish_gaussian's tile mask: tile_touched for W tiles of the rectangle r at a time (row-major,
// bit b = tile b of the rectangle), the same operations lane by lane.
template <int W>
WGS_ALWAYS_INLINE uint64_t tile_mask_v(const float* sp, float inv_ca, float inv_cc, const int32_t* r, int area,
                                       int width, int height) {
  using vf = typename Lanes<W>::f;
  using vi = typename Lanes<W>::i;
  const int w = r[2] - r[0];
  const float ca = sp[2], cb = sp[3], cc = sp[4], q_max = sp[11];
  // Tile b of the rectangle is (b % w, b / w), the row taken as (b * ceil(4096 / w)) >> 12, exact for
  // b < 64 and w <= 64: vector integer operations instead of an integer division per lane (this
  // function took ~a fifth of the preprocess with them).
  const int32_t inv_w = (4096 + w - 1) / w;
  vi lane, lane_bit;
  for (int l = 0; l < W; ++l) lane[l] = l, lane_bit[l] = int32_t(1) << l;
  uint64_t mask = 0;
  for (int b0 = 0; b0 < area; b0 += W) {
    const vi b_raw = lane + b0;
    const vi b = b_raw < area - 1 ? b_raw : vi{} + (area - 1);  // the tail repeats the last tile
    const vi row = (b * inv_w) >> 12;
    const vi tx = (b - row * w) + r[0], ty = row + r[1];
    const vi tx_end = (tx + 1) * kTileSize, ty_end = (ty + 1) * kTileSize;
    vf x_lo = __builtin_convertvector(tx * kTileSize, vf);
    vf x_hi = __builtin_convertvector(tx_end < width ? tx_end : vi{} + width, vf);
    vf y_lo = __builtin_convertvector(ty * kTileSize, vf);
    vf y_hi = __builtin_convertvector(ty_end < height ? ty_end : vi{} + height, vf);
    x_lo = x_lo + 0.5f - sp[0]; x_hi = x_hi - 0.5f - sp[0];
    y_lo = y_lo + 0.5f - sp[1]; y_hi = y_hi - 0.5f - sp[1];
    const vi inside = (x_lo <= 0.0f) & (x_hi >= 0.0f) & (y_lo <= 0.0f) & (y_hi >= 0.0f);
    // Inlined by force: out of line they would pass 32-byte vectors through memory (-Wpsabi).
    auto q = [&](vf dx, vf dy) __attribute__((always_inline)) { return ca * dx * dx + 2.0f * cb * dx * dy + cc * dy * dy; };
    auto clamp = [](vf v, vf lo, vf hi) __attribute__((always_inline)) { return v < lo ? lo : (hi < v ? hi : v); };
    auto vmin = [](vf a, vf b) __attribute__((always_inline)) { return b < a ? b : a; };
    vf q_min = vf{} + std::numeric_limits<float>::infinity();
    q_min = vmin(q_min, q(x_lo, clamp(-cb * x_lo * inv_cc, y_lo, y_hi)));
    q_min = vmin(q_min, q(x_hi, clamp(-cb * x_hi * inv_cc, y_lo, y_hi)));
    q_min = vmin(q_min, q(clamp(-cb * y_lo * inv_ca, x_lo, x_hi), y_lo));
    q_min = vmin(q_min, q(clamp(-cb * y_hi * inv_ca, x_lo, x_hi), y_hi));
    const vi hit = (inside | (q_min <= q_max)) & (b_raw < area);
    const vi bits = hit & lane_bit;
    uint32_t block_bits = 0;  // distinct bits: the sum is their union
    for (int l = 0; l < W; ++l) block_bits += uint32_t(bits[l]);
    mask |= uint64_t(block_bits) << b0;
  }
  return mask;
}

// kTraining: also the per-Gaussian values only the backward pass reads (mean2d, cov2d, conic,
// opacity, color, scale, clamped).
template <int W, bool kTraining>
WGS_ALWAYS_INLINE void preprocess_block(const GaussianSet<float>& g, const RasterCamera<float>& cam, int degree,
                                        RasterState<float>* s, int64_t i0, int count) {
  using vf = typename Lanes<W>::f;
  using vi = typename Lanes<W>::i;
  int64_t lane[W];  // the Gaussian of each lane; the tail repeats the last one
  for (int l = 0; l < W; ++l) lane[l] = i0 + std::min(l, count - 1);
  // The SH coefficients (192 bytes per Gaussian) of the block after next: their loads were a
  // quarter of this function's time; fetched ahead the preprocess takes ~10 % less.
  constexpr int64_t kShAhead = 2 * W;
  if (i0 + kShAhead + W <= int64_t(g.size())) {
    const char* ahead = reinterpret_cast<const char*>(&g.sh[size_t(i0 + kShAhead) * kShFloats]);
    for (size_t b = 0; b < W * kShFloats * sizeof(float); b += 64) __builtin_prefetch(ahead + b);
  }
  vf px, py, pz, sx, sy, sz, qw, qx, qy, qz;
  for (int l = 0; l < W; ++l) {
    const int64_t i = lane[l];
    px[l] = g.position[i * 3]; py[l] = g.position[i * 3 + 1]; pz[l] = g.position[i * 3 + 2];
    sx[l] = g.log_scale[i * 3]; sy[l] = g.log_scale[i * 3 + 1]; sz[l] = g.log_scale[i * 3 + 2];
    qw[l] = g.rotation[i * 4]; qx[l] = g.rotation[i * 4 + 1];
    qy[l] = g.rotation[i * 4 + 2]; qz[l] = g.rotation[i * 4 + 3];
  }
  const Mat3<float>& R = cam.rotation;
  const Vec3<float>& tr = cam.translation;
  // Camera-space position (project_gaussian; its z is preprocess's culling depth, same sum).
  const vf cx = sum3(R(0, 0), px, R(0, 1), py, R(0, 2), pz) + tr.x();
  const vf cy = sum3(R(1, 0), px, R(1, 1), py, R(1, 2), pz) + tr.y();
  const vf z = sum3(R(2, 0), px, R(2, 1), py, R(2, 2), pz) + tr.z();
  const auto in_front = z > float(kNearPlane);

  // covariance_3d: M = R(q) diag(exp(log_scale)), Sigma = M M^T.
  sx = exp_v<W>(sx); sy = exp_v<W>(sy); sz = exp_v<W>(sz);
  const vf qn = lanewise((qw * qw + qy * qy) + (qx * qx + qz * qz), [](float v) { return std::sqrt(v); });
  const auto q_ok = qn >= float(kMinQuatNorm);
  const vf w = qw / qn, x = qx / qn, y = qy / qn, zq = qz / qn;
  const vf one = vf{} + 1.0f, zero = vf{};
  const vf r00 = q_ok ? 1.0f - 2.0f * (y * y + zq * zq) : one;
  const vf r01 = q_ok ? 2.0f * (x * y - w * zq) : zero;
  const vf r02 = q_ok ? 2.0f * (x * zq + w * y) : zero;
  const vf r10 = q_ok ? 2.0f * (x * y + w * zq) : zero;
  const vf r11 = q_ok ? 1.0f - 2.0f * (x * x + zq * zq) : one;
  const vf r12 = q_ok ? 2.0f * (y * zq - w * x) : zero;
  const vf r20 = q_ok ? 2.0f * (x * zq - w * y) : zero;
  const vf r21 = q_ok ? 2.0f * (y * zq + w * x) : zero;
  const vf r22 = q_ok ? 1.0f - 2.0f * (x * x + y * y) : one;
  const vf m00 = r00 * sx, m01 = r01 * sy, m02 = r02 * sz;
  const vf m10 = r10 * sx, m11 = r11 * sy, m12 = r12 * sz;
  const vf m20 = r20 * sx, m21 = r21 * sy, m22 = r22 * sz;
  const vf s00 = sum3(m00, m00, m01, m01, m02, m02), s01 = sum3(m00, m10, m01, m11, m02, m12);
  const vf s02 = sum3(m00, m20, m01, m21, m02, m22), s11 = sum3(m10, m10, m11, m11, m12, m12);
  const vf s12 = sum3(m10, m20, m11, m21, m12, m22), s22 = sum3(m20, m20, m21, m21, m22, m22);

  // project_gaussian: mean, clamped Jacobian J, T = J R_cam, cov = (T Sigma) T^T + low-pass.
  const vf iz = 1.0f / z;
  const vf mean_x = cam.fx * cx * iz + cam.cx, mean_y = cam.fy * cy * iz + cam.cy;
  const vf rx = cx * iz, ry = cy * iz;
  const vf tx = (rx < cam.lim_x_lo ? vf{} + cam.lim_x_lo : (cam.lim_x_hi < rx ? vf{} + cam.lim_x_hi : rx)) * z;
  const vf ty = (ry < cam.lim_y_lo ? vf{} + cam.lim_y_lo : (cam.lim_y_hi < ry ? vf{} + cam.lim_y_hi : ry)) * z;
  const vf j00 = cam.fx * iz, j02 = -cam.fx * tx * iz * iz;
  const vf j11 = cam.fy * iz, j12 = -cam.fy * ty * iz * iz;
  vf t0[3], t1[3];
  for (int k = 0; k < 3; ++k) {
    t0[k] = j00 * R(0, k) + (0.0f * R(1, k) + j02 * R(2, k));
    t1[k] = 0.0f * R(0, k) + (j11 * R(1, k) + j12 * R(2, k));
  }
  const vf sig[3][3] = {{s00, s01, s02}, {s01, s11, s12}, {s02, s12, s22}};
  vf u0[3], u1[3];  // T Sigma
  for (int k = 0; k < 3; ++k) {
    u0[k] = sum3(t0[0], sig[0][k], t0[1], sig[1][k], t0[2], sig[2][k]);
    u1[k] = sum3(t1[0], sig[0][k], t1[1], sig[1][k], t1[2], sig[2][k]);
  }
  const vf cov_a = sum3(u0[0], t0[0], u0[1], t0[1], u0[2], t0[2]) + cam.low_pass;
  const vf cov_b = sum3(u0[0], t1[0], u0[1], t1[1], u0[2], t1[2]);
  const vf cov_c = sum3(u1[0], t1[0], u1[1], t1[1], u1[2], t1[2]) + cam.low_pass;

  // sh_to_color along view_direction.
  const vf vx = px - cam.center_world.x(), vy = py - cam.center_world.y(), vz = pz - cam.center_world.z();
  const vf len = lanewise(vx * vx + (vy * vy + vz * vz), [](float v) { return std::sqrt(v); });
  const auto has_len = len > 0.0f;
  const vf dx = has_len ? vx / len : zero, dy = has_len ? vy / len : zero, dz = has_len ? vz / len : zero;
  vf b[kShCoeffs] = {};
  b[0] = vf{} + float(kShC0);
  if (degree >= 1) {
    b[1] = -float(kShC1) * dy;
    b[2] = float(kShC1) * dz;
    b[3] = -float(kShC1) * dx;
  }
  if (degree >= 2) {
    const vf xx = dx * dx, yy = dy * dy, zz = dz * dz;
    b[4] = float(kShC2[0]) * dx * dy;
    b[5] = float(kShC2[1]) * dy * dz;
    b[6] = float(kShC2[2]) * (2.0f * zz - xx - yy);
    b[7] = float(kShC2[3]) * dx * dz;
    b[8] = float(kShC2[4]) * (xx - yy);
    if (degree >= 3) {
      b[9] = float(kShC3[0]) * dy * (3.0f * xx - yy);
      b[10] = float(kShC3[1]) * dx * dy * dz;
      b[11] = float(kShC3[2]) * dy * (4.0f * zz - xx - yy);
      b[12] = float(kShC3[3]) * dz * (2.0f * zz - 3.0f * xx - 3.0f * yy);
      b[13] = float(kShC3[4]) * dx * (4.0f * zz - xx - yy);
      b[14] = float(kShC3[5]) * dz * (xx - yy);
      b[15] = float(kShC3[6]) * dx * (xx - 3.0f * yy);
    }
  }
  const int n_coeffs = (degree + 1) * (degree + 1);
  // The lanes' SH coefficients, coefficient-major: W rows of W consecutive floats (one row per
  // Gaussian) transposed in registers, instead of one scalar load per lane and coefficient.
  vf coef[kShFloats];
  for (int f0 = 0; f0 < n_coeffs * 3; f0 += W) {
    vf rows[W];
    for (int l = 0; l < W; ++l) rows[l] = load_v<vf>(&g.sh[lane[l] * kShFloats + f0]);
    transpose<W>(rows);
    for (int c = 0; c < W; ++c) coef[f0 + c] = rows[c];
  }
  vf col[3] = {vf{} + 0.5f, vf{} + 0.5f, vf{} + 0.5f};
  for (int k = 0; k < n_coeffs; ++k)
    for (int ch = 0; ch < 3; ++ch) col[ch] += b[k] * coef[k * 3 + ch];

  // finish_gaussian, lane by lane the same operations, up to the tile mask.
  vf rgb[3];
  typename Lanes<W>::i clamped_bits = {};
  for (int ch = 0; ch < 3; ++ch) {
    const auto neg = col[ch] < 0.0f;
    rgb[ch] = neg ? zero : col[ch];
    clamped_bits |= neg & (1 << ch);
  }
  const vf det = cov_a * cov_c - cov_b * cov_b;
  const vf mid = 0.5f * (cov_a + cov_c);
  const vf gap = mid * mid - det;
  const vf root = lanewise(float(kMinEigenGap) < gap ? gap : vf{} + float(kMinEigenGap),
                           [](float v) { return std::sqrt(v); });
  const vf hi_root = mid + root, lo_root = mid - root;
  const vf lambda = hi_root < lo_root ? lo_root : hi_root;
  const vf radius = lanewise(3.0f * lanewise(lambda, [](float v) { return std::sqrt(v); }),
                             [](float v) { return std::ceil(v); });
  const vf con_a = cov_c / det, con_b = -cov_b / det, con_c = cov_a / det;
  auto finite = [](vf v) __attribute__((always_inline)) { return v - v == 0.0f; };
  auto ok = in_front & (det > 0.0f) & finite(mean_x) & finite(mean_y) & finite(cov_a) & finite(cov_b) &
            finite(cov_c) & finite(radius) & finite(con_a) & finite(con_b) & finite(con_c);
  const vf cx0 = mean_x - 0.5f, cy0 = mean_y - 0.5f;
  const int gx = reference_tiles(s->width), gy = reference_tiles(s->height);
  const vi x0 = tile_floor_v<W>(cx0 - radius, gx), y0 = tile_floor_v<W>(cy0 - radius, gy);
  const vi x1 = tile_floor_v<W>(cx0 + radius + float(kReferenceTile - 1), gx);
  const vi y1 = tile_floor_v<W>(cy0 + radius + float(kReferenceTile - 1), gy);
  ok &= ((x1 - x0) * (y1 - y0) != 0) & finite(rgb[0]) & finite(rgb[1]) & finite(rgb[2]);
  // sigmoid and alpha_q_max (-1 where the opacity is below 1/255 or NaN).
  vf logit;
  for (int l = 0; l < W; ++l) logit[l] = g.opacity_logit[lane[l]];
  const vi positive = logit >= 0.0f;
  const vf e = exp_v<W>(positive ? -logit : logit);
  const vf opacity = positive ? 1.0f / (1.0f + e) : e / (1.0f + e);
  const vi has_alpha = opacity >= float(kAlphaMin);
  const vf q_max = has_alpha ? 2.0f * log_v<W>(has_alpha ? 255.0f * opacity : vf{} + 1.0f) : vf{} - 1.0f;
  const auto no_alpha = q_max < 0.0f;
  const vf ext_x = no_alpha ? vf{} - 1.0f : lanewise(q_max * cov_a, [](float v) { return std::sqrt(v); }) + 1.0f;
  const vf ext_y = no_alpha ? vf{} - 1.0f : lanewise(q_max * cov_c, [](float v) { return std::sqrt(v); }) + 1.0f;
  const vf q_lim = no_alpha ? vf{} - 1.0f : q_max * float(1.0001) + float(1e-3);
  const vf inv_ca = 1.0f / con_a, inv_cc = 1.0f / con_c;

  for (int l = 0; l < count; ++l) {
    const int64_t i = i0 + l;
    clear_gaussian(s, i);
    if (!ok[l]) continue;
    s->radius[i] = int32_t(std::min<float>(radius[l], float(std::numeric_limits<int32_t>::max() / 2)));
    if constexpr (kTraining) {
      s->mean2d[i * 2] = mean_x[l]; s->mean2d[i * 2 + 1] = mean_y[l];
      s->cov2d[i * 3] = cov_a[l]; s->cov2d[i * 3 + 1] = cov_b[l]; s->cov2d[i * 3 + 2] = cov_c[l];
      s->conic[i * 3] = con_a[l]; s->conic[i * 3 + 1] = con_b[l]; s->conic[i * 3 + 2] = con_c[l];
      s->opacity[i] = opacity[l];
      for (int ch = 0; ch < 3; ++ch) s->color[i * 3 + ch] = rgb[ch][l];
      s->scale[i * 3] = sx[l]; s->scale[i * 3 + 1] = sy[l]; s->scale[i * 3 + 2] = sz[l];
      s->clamped[i] = uint8_t(clamped_bits[l]);
    }
    s->depth[i] = z[l];
    float* sp = &s->splat[i * kSplatFloats];
    sp[0] = mean_x[l]; sp[1] = mean_y[l]; sp[2] = con_a[l]; sp[3] = con_b[l]; sp[4] = con_c[l];
    sp[5] = opacity[l]; sp[6] = rgb[0][l]; sp[7] = rgb[1][l]; sp[8] = rgb[2][l];
    sp[9] = ext_x[l]; sp[10] = ext_y[l]; sp[11] = q_lim[l];
    int32_t* r = &s->rect[i * 4];
    set_pixel_box(s, sp, x0[l], y0[l], x1[l], y1[l], r);  // a few scalar operations per lane, as in the template
    const int w = r[2] - r[0], h = r[3] - r[1], area = w * h;
    if (area > 0 && area <= kMaskTiles) {
      uint64_t mask = area == kMaskTiles ? ~uint64_t(0) : (uint64_t(1) << area) - 1;
      if (w > 1 && h > 1) mask = tile_mask_v<W>(sp, inv_ca[l], inv_cc[l], r, area, s->width, s->height);
      s->tile_mask[i] = mask;
      if (mask == 0) r[0] = r[1] = r[2] = r[3] = 0;
    }
  }
}

template <int W>
WGS_ALWAYS_INLINE void preprocess_range(const GaussianSet<float>& g, const RasterCamera<float>& cam, int degree,
                                        bool training, RasterState<float>* s, int64_t lo, int64_t hi) {
  for (int64_t i = lo; i < hi; i += W) {
    const int count = int(std::min<int64_t>(W, hi - i));
    if (training) preprocess_block<W, true>(g, cam, degree, s, i, count);
    else preprocess_block<W, false>(g, cam, degree, s, i, count);
  }
}

void preprocess_w4(const GaussianSet<float>& g, const RasterCamera<float>& cam, int degree, bool training,
                   RasterState<float>* s, int64_t lo, int64_t hi) {
  preprocess_range<4>(g, cam, degree, training, s, lo, hi);
}
#if defined(__x86_64__) && defined(__GNUC__)
#define WGS_WIDE_PREPROCESS 1
__attribute__((target("avx2"))) void preprocess_w8(const GaussianSet<float>& g, const RasterCamera<float>& cam,
                                                   int degree, bool training, RasterState<float>* s, int64_t lo,
                                                   int64_t hi) {
  preprocess_range<8>(g, cam, degree, training, s, lo, hi);
}
#endif

}  // namespace

void preprocess_simd(const GaussianSet<float>& g, const RasterCamera<float>& cam, const RasterSettings<float>& settings,
                     RasterState<float>* s) {
  const int width = tile_kernel_width();
  const bool training = settings.outputs == RasterOutputs::kTraining;
  parallel_for_chunks(0, int64_t(g.size()), kGaussianChunk, [&](int64_t, int64_t lo, int64_t hi) {
#ifdef WGS_WIDE_PREPROCESS
    if (width == 8) return preprocess_w8(g, cam, settings.sh_degree, training, s, lo, hi);
#endif
    preprocess_w4(g, cam, settings.sh_degree, training, s, lo, hi);
  });
}

}  // namespace weathergs::reconstruction::internal
