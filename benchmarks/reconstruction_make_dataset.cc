// Writes the synthetic dataset of the `weathergs train` benchmark (benchmarks/README.md):
//   bench_reconstruction_make_dataset OUT [width height views]
// A textured ground disc of flat Gaussians and a cluster of coloured blobs, rendered by our own
// forward pass from a ring of cameras (LLFF splits), with the jittered centres of every fourth
// Gaussian as the COLMAP points3D.txt.
#include <cstdio>
#include <cstdlib>

#include "tests/reconstruction/test_scene.h"

using namespace weathergs;
using namespace weathergs::reconstruction;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s OUT [width height views]\n", argv[0]);
    return 2;
  }
  const int width = argc > 2 ? std::atoi(argv[2]) : 300, height = argc > 3 ? std::atoi(argv[3]) : 200;
  const int views = argc > 4 ? std::atoi(argv[4]) : 24;
  const int ground = 24000, blobs = 6000;
  GaussianSet<float> g;
  g.assign_zero(ground + blobs);
  for (int i = 0; i < ground + blobs; ++i) {
    Rng rng(7, 1, i);
    float* p = &g.position[i * 3];
    float* sh = &g.sh[i * kShFloats];
    if (i < ground) {  // disc of radius 3 m at z = -0.8, flat Gaussians, stripes and noise
      const double r = 3.0 * std::sqrt(rng.uniform_double()), a = 2 * M_PI * rng.uniform_double();
      p[0] = float(r * std::cos(a)); p[1] = float(r * std::sin(a)); p[2] = -0.8f;
      g.log_scale[i * 3] = g.log_scale[i * 3 + 1] = float(std::log(0.035));
      g.log_scale[i * 3 + 2] = float(std::log(0.002));
      const double stripe = 0.5 + 0.5 * std::sin(4.0 * p[0]) * std::cos(3.0 * p[1]);
      const double rgb[3] = {0.25 + 0.5 * stripe, 0.3 + 0.2 * rng.uniform_double(), 0.6 - 0.4 * stripe};
      for (int c = 0; c < 3; ++c) sh[c] = float(rgb_to_sh0(rgb[c]));
      g.rotation[i * 4] = 1;
      g.opacity_logit[i] = 3.f;
    } else {  // blobs in a 1 m ball, some view dependence
      double x, y, z;
      do { x = rng.uniform(-1, 1); y = rng.uniform(-1, 1); z = rng.uniform(-1, 1); } while (x * x + y * y + z * z > 1);
      p[0] = float(x * 0.9); p[1] = float(y * 0.9); p[2] = float(z * 0.6);
      for (int k = 0; k < 3; ++k) g.log_scale[i * 3 + k] = float(std::log(0.02) + rng.uniform(0.f, 1.2f));
      for (int k = 0; k < 4; ++k) g.rotation[i * 4 + k] = float(rng.normal());
      g.opacity_logit[i] = float(rng.uniform(-1.f, 3.f));
      for (int c = 0; c < 3; ++c) sh[c] = float(rgb_to_sh0(rng.uniform(0.05f, 0.95f)));
      for (int k = 3; k < 12; ++k) sh[k] = float(0.15 * rng.normal());
    }
  }
  std::vector<Camera> cams;
  for (int i = 0; i < views; ++i) {
    const double a = 2 * M_PI * i / views;
    char name[16];
    std::snprintf(name, sizeof name, "%03d", i);
    cams.push_back(testing::look_at_camera(name, width, height, 0.8 * width,
                                           Eigen::Vector3d(3.6 * std::cos(a), 3.6 * std::sin(a), 1.4)));
  }
  // Points: every fourth Gaussian (a sparse SfM-like cloud), jittered by 1 cm.
  GaussianSet<float> pts;
  pts.assign_zero((ground + blobs) / 4);
  for (size_t i = 0; i < pts.size(); ++i) pts.copy_from(g, i * 4, i);
  testing::write_synthetic_dataset(argv[1], g, cams, false);
  // write_synthetic_dataset renders `g`; the points come from the subset.
  testing::write_synthetic_dataset(std::string(argv[1]) + ".points_tmp", pts, cams, true);
  std::filesystem::create_directories(std::string(argv[1]) + "/sparse");
  std::filesystem::rename(std::string(argv[1]) + ".points_tmp/sparse/0", std::string(argv[1]) + "/sparse/0");
  std::filesystem::remove_all(std::string(argv[1]) + ".points_tmp");
  std::printf("wrote %s: %d views %dx%d, %zu Gaussians, %zu points\n", argv[1], views, width, height, g.size(), pts.size());
  return 0;
}
