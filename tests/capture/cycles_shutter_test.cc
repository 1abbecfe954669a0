// The path-tracer reference of the compositor validation moves particles over the shutter: a sphere
// moving across the view must be smeared over exactly its projected path (start and end known), and a
// sphere covers its disc.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/image.h"
#include "capture/blender.h"
#include "capture/process.h"
#include "tests/core/test_util.h"

namespace weathergs::capture {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// The smear's ends are found to the pixel: the sphere's disc (2.7 px radius) at both ends, edges
// where more than a tenth of the disc covers the pixel.
constexpr double kEndTolerancePx = 1.5;

// Writes `job` into `dir`, renders it with Blender and returns whether it ran.
::testing::AssertionResult render_job(Json job, const fs::path& dir) {
  job["output_dir"] = dir / "render";
  fs::create_directories(dir / "render");
  write_file_atomic(dir / "job.json", job.dump());
  ProcessOptions popts;
  popts.log_path = dir / "blender.log";
  const ProcessResult r = run_blender_job("blender", testing::blender_script(), dir / "job.json", "blender", popts);
  if (r.exit_code == 0) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "blender exited " << r.exit_code << "\n" << tail_of_file(popts.log_path, 30);
}

// Blender leaves its session folder (blender_XXXXXX in $TMPDIR) behind when the script raises, as it
// does for every bad job; run_blender_job gives it a TMPDIR of its own and removes it, so a failed
// render leaves nothing in the caller's temporary folder.
TEST(BlenderJobTest, AFailedJobLeavesNoTemporaryFolder) {
  if (find_executable("blender").empty()) GTEST_SKIP() << "blender not installed";
  TempDir tmp;
  const fs::path parent_tmp = tmp / "parent_tmp", job_dir = tmp / "job";
  fs::create_directories(parent_tmp);
  fs::create_directories(job_dir / "render");
  const char* old_tmpdir = std::getenv("TMPDIR");
  const std::string saved = old_tmpdir ? old_tmpdir : "";
  ASSERT_EQ(::setenv("TMPDIR", parent_tmp.c_str(), 1), 0);
  write_file_atomic(job_dir / "job.json", Json{{"output_dir", job_dir / "render"}}.dump());  // no scene: the script raises
  ProcessOptions popts;
  popts.log_path = job_dir / "blender.log";
  const ProcessResult r = run_blender_job("blender", testing::blender_script(), job_dir / "job.json", "blender", popts);
  if (old_tmpdir) ::setenv("TMPDIR", saved.c_str(), 1); else ::unsetenv("TMPDIR");
  EXPECT_EQ(r.exit_code, 1) << tail_of_file(popts.log_path, 30);
  EXPECT_TRUE(fs::exists(job_dir / "render" / "error.json"));
  EXPECT_TRUE(fs::is_empty(parent_tmp)) << fs::directory_iterator(parent_tmp)->path();
  for (const auto& e : fs::directory_iterator(job_dir))  // job.json, blender.log, render/ only
    EXPECT_TRUE(e.path().filename() == "job.json" || e.path().filename() == "blender.log" ||
                e.path().filename() == "render") << e.path();
}

Json one_particle(const Camera& cam, const Eigen::Vector3d& p, const Eigen::Vector3d& v, double radius) {
  const Json item = {{"kind", "snow"}, {"radius_m", radius}, {"p_world", {p.x(), p.y(), p.z()}}, {"v_world", {v.x(), v.y(), v.z()}}};
  return {{"exposure_s", cam.exposure_s}, {"items", Json::array({item})}};
}

// A sphere crossing pool's first view: 1.5 m ahead, starting 0.2 m left of the axis, moving right
// by `travel` over the exposure. Jobs for two views of that camera named a and b.
struct Crossing {
  SceneSpec scene = read_scene_spec(std::string(WEATHERGS_SOURCE_DIR) + "/scenes/pool.json");
  ProfileSpec profile;
  Camera cam;
  Eigen::Vector3d p0, v;
  Crossing(const ProfileSpec& p, double travel) : profile(p), cam(scene_cameras(scene, p)[0]) {
    const Eigen::Vector3d forward = cam.rotation().row(2).transpose(), right = cam.rotation().row(0).transpose();
    p0 = cam.center_world() + 1.5 * forward - 0.2 * right;
    v = right * travel / cam.exposure_s;
  }
  Json job(const std::string& a, const std::string& b) const {
    Camera ca = cam, cb = cam;
    ca.name = a;
    cb.name = b;
    return blender_job(scene, scene.variant("clear"), profile, {ca, cb}, {});
  }
};

TEST(CyclesShutterTest, MotionBlurCoversTheProjectedPath) {
  if (find_executable("blender").empty()) GTEST_SKIP() << "blender not installed";
  const Crossing crossing({"shutter", 300, 200, 1, 32, "cycles"}, 0.4);
  const Camera& cam = crossing.cam;
  const Eigen::Vector3d p0 = crossing.p0, v = crossing.v;
  const double radius = 0.02;
  TempDir tmp;
  Json job = crossing.job("plain", "moving");
  job["camera"]["views"][0]["particles"] = false;
  job["camera"]["views"][1]["particles"] = true;
  job["particles"] = one_particle(cam, p0, v, radius);
  ASSERT_TRUE(render_job(job, tmp.path()));

  const Image a = read_image(tmp / "render/clean/plain.png");
  const Image b = read_image(tmp / "render/clean/moving.png");
  const Eigen::Vector2d start = *cam.project(p0), end = *cam.project(p0 + v * cam.exposure_s);
  const double r_px = cam.fx * radius / 1.5;
  // A band around the path: the sun also moves the sphere's shadow across the deck below it.
  int x_min = 1 << 30, x_max = -1, y_min = 1 << 30, y_max = -1;
  for (int y = int(start.y()) - 12; y <= int(start.y()) + 12; ++y)
    for (int x = 0; x < a.width; ++x) {
      double d = 0;
      for (int c = 0; c < 3; ++c) d += std::abs(a.at(x, y, c) - b.at(x, y, c));
      if (d > 0.04) x_min = std::min(x_min, x), x_max = std::max(x_max, x), y_min = std::min(y_min, y), y_max = std::max(y_max, y);
    }
  ASSERT_GE(x_max, 0) << "the moving sphere is not in the render";
  // The smear spans from the start disc's left edge to the end disc's right edge.
  EXPECT_NEAR(x_min + 0.5, start.x() - r_px, r_px + kEndTolerancePx);
  EXPECT_NEAR(x_max + 0.5, end.x() + r_px, r_px + kEndTolerancePx);
  EXPECT_NEAR(x_min + 0.5, start.x(), kEndTolerancePx + r_px);
  EXPECT_NEAR(0.5 * (y_min + y_max + 1), start.y(), kEndTolerancePx);
  EXPECT_LE(y_max - y_min + 1, 2 * r_px + 2 * kEndTolerancePx);
  // Without motion blur (or with a shutter twice too long) the smear would be 2r or ~2x longer.
  EXPECT_NEAR(x_max - x_min, end.x() - start.x(), 2 * r_px + kEndTolerancePx);
  std::printf("smear x %d-%d y %d-%d; path x %.1f-%.1f y %.1f, radius %.1f px\n", x_min, x_max, y_min, y_max,
              start.x(), end.x(), start.y(), r_px);
}

// A polyhedron's projected area varies with its orientation around the mean the reference scales to
// pi r^2 (Cauchy): measured on the axis at 32 samples, the 320-face sphere covers 0.999 of the disc;
// unscaled it would cover 0.98 of it (80 faces, the reference's sphere before: 0.93).
constexpr double kCoverageTolerance = 0.01;

// One static sphere on the optical axis, rendered as coverage (opaque white over a transparent film,
// float): the summed coverage is the area of the sphere's image, the disc of radius
// f r / sqrt(D^2 - r^2). The sphere is an instance scaled by its radius (blender_scripts: moving_spheres).
TEST(CyclesShutterTest, TheSphereCoversItsDisc) {
  if (find_executable("blender").empty()) GTEST_SKIP() << "blender not installed";
  const SceneSpec scene = read_scene_spec(std::string(WEATHERGS_SOURCE_DIR) + "/scenes/pool.json");
  ProfileSpec profile{"coverage", 300, 200, 1, 32, "cycles"};
  Camera cam = scene_cameras(scene, profile)[0];
  cam.name = "coverage";
  const Eigen::Vector3d forward = cam.rotation().row(2).transpose();
  const double radius = 0.1, distance = 1.5;
  const Eigen::Vector3d p = cam.center_world() + distance * forward;
  const double disc_px = M_PI * std::pow(cam.fx * radius / std::sqrt(distance * distance - radius * radius), 2);
  TempDir tmp;
  Json job = blender_job(scene, scene.variant("clear"), profile, {cam}, {});
  job["camera"]["views"][0]["coverage"] = true;
  job["render"]["float_images"] = true;
  job["particles"] = one_particle(cam, p, Eigen::Vector3d::Zero(), radius);
  ASSERT_TRUE(render_job(job, tmp.path()));
  const Image c = read_image(tmp / "render/clean/coverage.exr");
  double covered = 0;
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x) covered += c.at(x, y, 0);
  EXPECT_NEAR(covered / disc_px, 1.0, kCoverageTolerance);
  std::printf("coverage %.1f px^2, disc %.1f px^2 (%.4f)\n", covered, disc_px, covered / disc_px);
}

// A view's own "samples" overrides the job's (the validation renders its coverage view with more):
// one sample per pixel leaves every pixel of a moving sphere's smear at 0 or 1 (one time sample,
// one filter sample), 64 samples leave fractional coverage along the whole smear.
TEST(CyclesShutterTest, AViewMayAskForItsOwnSampleCount) {
  if (find_executable("blender").empty()) GTEST_SKIP() << "blender not installed";
  const Crossing crossing({"samples", 120, 80, 1, 64, "cycles"}, 0.4);
  TempDir tmp;
  Json job = crossing.job("one", "many");
  for (int i = 0; i < 2; ++i) job["camera"]["views"][i]["coverage"] = true;
  job["camera"]["views"][0]["samples"] = 1;
  job["render"]["float_images"] = true;
  job["particles"] = one_particle(crossing.cam, crossing.p0, crossing.v, 0.02);
  ASSERT_TRUE(render_job(job, tmp.path()));
  auto fractional = [&](const std::string& name, int* covered) {
    const Image c = read_image(tmp / ("render/clean/" + name + ".exr"));
    int n = 0;
    *covered = 0;
    for (float v : c.data) n += v > 0.01f && v < 0.99f, *covered += v > 0.01f;
    return n;
  };
  int covered_one = 0, covered_many = 0;
  const int frac_one = fractional("one", &covered_one), frac_many = fractional("many", &covered_many);
  ASSERT_GT(covered_many, 30) << "the smear is not in the view";
  EXPECT_EQ(frac_one, 0) << "1 sample per pixel gives only 0 or 1";
  EXPECT_GT(frac_many, covered_many / 2);
}

}  // namespace
}  // namespace weathergs::capture
