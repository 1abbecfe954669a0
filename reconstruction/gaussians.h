// A set of 3D Gaussians in structure-of-arrays layout, the standard 3DGS PLY file, and the
// initialization from a point cloud.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "reconstruction/gaussian_math.h"

namespace weathergs::reconstruction {

// Parameters in the optimizer's (pre-activation) space, as in the reference GaussianModel:
// scale = exp(log_scale), rotation = normalize(quaternion), opacity = sigmoid(opacity_logit).
// The same type holds gradients and Adam moments (same shapes).
template <typename T>
struct GaussianSet {
  std::vector<T> position;       // N x 3, world frame (meters)
  std::vector<T> log_scale;      // N x 3
  std::vector<T> rotation;       // N x 4, quaternion (w, x, y, z), unnormalized
  std::vector<T> opacity_logit;  // N
  std::vector<T> sh;             // N x 16 x 3: coefficient k, channel c at [i * 48 + k * 3 + c]

  size_t size() const { return opacity_logit.size(); }
  void resize(size_t n);               // new entries are zero
  void assign_zero(size_t n);          // size n, all zero
  void copy_from(const GaussianSet& o, size_t from, size_t to);  // row `to` = o's row `from`
  void keep(const std::vector<char>& keep_mask);  // removes rows whose mask is 0, order kept

  template <typename U>
  GaussianSet<U> cast() const {
    GaussianSet<U> o;
    auto c = [](const std::vector<T>& a) { return std::vector<U>(a.begin(), a.end()); };
    o.position = c(position); o.log_scale = c(log_scale); o.rotation = c(rotation);
    o.opacity_logit = c(opacity_logit); o.sh = c(sh);
    return o;
  }
};

// Parameter groups (the reference's optimizer groups), for learning rates and error messages.
enum class ParamGroup { kPosition, kShDc, kShRest, kOpacity, kScale, kRotation };
const char* to_string(ParamGroup g);

// RGB in [0, 1] <-> degree-0 SH coefficient (the reference's RGB2SH / SH2RGB).
inline double rgb_to_sh0(double rgb) { return (rgb - 0.5) / kShC0; }
inline double sh0_to_rgb(double sh) { return sh * kShC0 + 0.5; }
inline double inverse_sigmoid(double p) { return std::log(p / (1.0 - p)); }

// Standard 3DGS PLY (binary little endian): x y z nx ny nz f_dc_0..2 f_rest_0..44 opacity
// scale_0..2 rot_0..3, with f_rest channel-major (f_rest_{c*15 + k-1} = SH coefficient k, channel c).
void write_ply(const std::string& path, const GaussianSet<float>& g);
// Reads that layout (f_rest may hold 0, 9, 24 or 45 values; missing ones are zero). Property order
// may differ and extra properties are ignored; a missing required property is an InputError.
GaussianSet<float> read_ply(const std::string& path);

struct InitOptions {
  double initial_opacity = 0.1;  // reference: inverse_sigmoid(0.1)
  double min_dist2 = 1e-7;       // reference: clamp of the mean squared 3-NN distance
};
// Gaussians at the points with their colours (sRGB in [0, 1] -> SH DC), isotropic scale = sqrt of the
// mean squared distance to the 3 nearest neighbours, identity rotation (create_from_pcd).
GaussianSet<float> init_from_points(const std::vector<Eigen::Vector3d>& points_world,
                                    const std::vector<Eigen::Vector3d>& colors_rgb01,
                                    const InitOptions& options = {});

// Mean squared distance of each point to its 3 nearest other points (distCUDA2); exact, via a k-d tree.
std::vector<double> mean_sq_dist_3nn(const std::vector<Eigen::Vector3d>& points);

}  // namespace weathergs::reconstruction
