// `weathergs import`: footage of a synthetic textured room (ray cast here, so the true cameras are
// known) goes through a video file, keyframe extraction and COLMAP's mapper; the recovered cameras
// match the truth up to a similarity transform. Bad inputs fail clearly and leave nothing behind.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/error.h"
#include "datagen/import.h"
#include "datagen/process.h"
#include "tests/core/test_util.h"

namespace weathergs::datagen {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// Mapper poses are up to a similarity; after aligning, camera centers of a 1.6 m path agree to a few
// centimeters at 320x240 (sub-pixel features at 2-4 m depth).
constexpr double kCenterToleranceM = 0.05;

uint32_t hash3(int x, int y, int z) {
  uint32_t h = uint32_t(x) * 73856093u ^ uint32_t(y) * 19349663u ^ uint32_t(z) * 83492791u;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  return h ^ (h >> 15);
}

// Multi-octave value noise in [0, 1]: non-repeating texture with features at every scale.
double texture(double u, double v, int plane) {
  double sum = 0, amp = 0.5;
  for (int o = 0; o < 5; ++o) {
    const double s = 4.0 * (1 << o);
    const int iu = int(std::floor(u * s)), iv = int(std::floor(v * s));
    const double fu = u * s - iu, fv = v * s - iv;
    auto val = [&](int a, int b) { return (hash3(a, b, plane * 16 + o) & 0xffff) / 65535.0; };
    const double a = val(iu, iv) * (1 - fu) + val(iu + 1, iv) * fu;
    const double b = val(iu, iv + 1) * (1 - fu) + val(iu + 1, iv + 1) * fu;
    sum += amp * (a * (1 - fv) + b * fv);
    amp *= 0.5;
  }
  return sum / (1 - std::pow(0.5, 5));
}

// A room corner: floor z = 0, back wall y = 4, left wall x = -2, right wall x = 2.
cv::Mat render_room(const Camera& cam) {
  cv::Mat img(cam.height, cam.width, CV_8UC3);
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const Eigen::Vector3d o = cam.center_world();
      const Eigen::Vector3d d = cam.ray_direction_world({x + 0.5, y + 0.5});
      double best = 1e9, c = 0;
      int plane = -1;
      auto hit = [&](double t, int p, double u, double v) {
        if (t > 1e-6 && t < best) best = t, plane = p, c = texture(u, v, p);
      };
      if (d.z() < 0) { double t = -o.z() / d.z(); Eigen::Vector3d q = o + t * d; hit(t, 0, q.x(), q.y()); }
      if (d.y() > 0) { double t = (4 - o.y()) / d.y(); Eigen::Vector3d q = o + t * d; hit(t, 1, q.x(), q.z()); }
      if (d.x() < 0) { double t = (-2 - o.x()) / d.x(); Eigen::Vector3d q = o + t * d; hit(t, 2, q.y(), q.z()); }
      if (d.x() > 0) { double t = (2 - o.x()) / d.x(); Eigen::Vector3d q = o + t * d; hit(t, 3, q.y(), q.z()); }
      const double tint[4][3] = {{0.9, 0.8, 0.6}, {0.6, 0.8, 0.9}, {0.9, 0.6, 0.6}, {0.6, 0.9, 0.6}};
      for (int ch = 0; ch < 3; ++ch)
        img.at<cv::Vec3b>(y, x)[2 - ch] = cv::saturate_cast<uint8_t>(plane < 0 ? 200 : 255 * c * tint[plane][ch]);
    }
  return img;
}

std::vector<Camera> room_path(int n) {
  std::vector<Camera> cams;
  for (int k = 0; k < n; ++k) {
    Camera c;
    c.name = std::to_string(k);
    c.width = 320, c.height = 240;
    c.fx = c.fy = 260, c.cx = 160, c.cy = 120;
    const Eigen::Vector3d center(-0.8 + 1.6 * k / (n - 1), -1.0 + 0.1 * std::sin(k), 1.2 + 0.15 * std::cos(0.7 * k));
    const Eigen::Vector3d target(0.0, 4.0, 0.8);
    const Eigen::Vector3d z = (target - center).normalized();
    const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d y = z.cross(x);
    Eigen::Matrix3d r;
    r.row(0) = x, r.row(1) = y, r.row(2) = z;
    c.camera_from_world.topLeftCorner<3, 3>() = r;
    c.camera_from_world.topRightCorner<3, 1>() = -r * center;
    cams.push_back(c);
  }
  return cams;
}

TEST(ImportTest, VideoOfAKnownRoom) {
  if (find_executable("colmap").empty()) GTEST_SKIP() << "colmap not installed";
  TempDir tmp;
  const int frames = 24, every = 2;
  const std::vector<Camera> truth = room_path(frames);
  const std::string video = tmp / "room.avi";
  {
    cv::VideoWriter writer(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 10.0, cv::Size(320, 240));
    ASSERT_TRUE(writer.isOpened()) << "OpenCV cannot write MJPG";
    for (const Camera& c : truth) writer.write(render_room(c));
  }
  ImportOptions o;
  o.video = video;
  o.every = every;
  o.weather = "clear";
  const std::string out = tmp / "room";
  const ImportSummary s = import_footage(o, out);
  EXPECT_EQ(s.frames, frames / every);
  EXPECT_GE(s.registered, s.frames - 1);
  EXPECT_LT(s.stats.mean_reprojection_error_px, 1.0);

  const Dataset ds = read_dataset(out);
  EXPECT_EQ(ds.info.name, "room");
  EXPECT_FALSE(ds.info.generator.has_value());
  ASSERT_TRUE(ds.info.source.has_value());
  EXPECT_EQ((*ds.info.source)["every"], every);
  EXPECT_FALSE(fs::exists(out + "/clean"));
  EXPECT_TRUE(fs::exists(out + "/sparse/0/points3D.txt"));
  EXPECT_TRUE(fs::exists(out + "/transforms.json"));
  // Align the recovered centers to the true ones (similarity) and compare.
  Eigen::Matrix3Xd src(3, ds.cameras.size()), dst(3, ds.cameras.size());
  for (size_t i = 0; i < ds.cameras.size(); ++i) {
    const Camera& c = ds.cameras[i];
    const int key = std::stoi(c.name);  // keyframe index: video frame key * every
    src.col(long(i)) = c.center_world();
    dst.col(long(i)) = truth[size_t(key * every)].center_world();
    EXPECT_NEAR(c.time_s, key * every / 10.0, 1e-6);
    EXPECT_EQ(c.width, 320);
  }
  const Eigen::Matrix4d sim = Eigen::umeyama(src, dst, true);
  for (long i = 0; i < src.cols(); ++i) {
    const Eigen::Vector3d p = (sim * src.col(i).homogeneous()).head<3>();
    EXPECT_LT((p - dst.col(i)).norm(), kCenterToleranceM) << ds.cameras[size_t(i)].name;
  }
}

TEST(ImportTest, BadInputsFailClearly) {
  TempDir tmp;
  auto expect_error = [&](ImportOptions o, const std::string& needle) {
    try {
      import_footage(o, tmp / "out");
      ADD_FAILURE() << "expected an InputError containing " << needle;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(tmp / "out"));
  };
  ImportOptions o;
  expect_error(o, "exactly one of");
  o.video = tmp / "missing.mp4";
  expect_error(o, "video file not found");
  o.video = tmp / "not_a_video.mp4";
  write_file_atomic(o.video, "this is text");
  expect_error(o, "cannot open this video");
  o.every = 0;
  expect_error(o, "every must be an integer >= 1");
  ImportOptions imgs;
  fs::create_directories(tmp / "two");
  cv::imwrite(tmp / "two/a.png", cv::Mat(64, 64, CV_8UC3, cv::Scalar(1, 2, 3)));
  cv::imwrite(tmp / "two/b.png", cv::Mat(64, 64, CV_8UC3, cv::Scalar(1, 2, 3)));
  imgs.images_dir = tmp / "two";
  expect_error(imgs, "at least 3 keyframes");
  cv::imwrite(tmp / "two/c.png", cv::Mat(32, 64, CV_8UC3, cv::Scalar(1, 2, 3)));
  expect_error(imgs, "one size");
  // Only the inputs are left in the scratch folder.
  EXPECT_EQ(testing::count_entries(tmp.path()), 2);
}

}  // namespace
}  // namespace weathergs::datagen
