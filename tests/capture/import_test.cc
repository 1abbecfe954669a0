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
#include "capture/import.h"
#include "capture/process.h"
#include "tests/core/test_util.h"
#include "tests/capture/room_scene.h"

namespace weathergs::capture {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// Mapper poses are up to a similarity; after aligning, camera centers of a 1.6 m path agree to a few
// centimeters at 320x240 (sub-pixel features at 2-4 m depth).
constexpr double kCenterToleranceM = 0.05;

TEST(ImportTest, VideoOfAKnownRoom) {
  if (find_executable("colmap").empty()) GTEST_SKIP() << "colmap not installed";
  TempDir tmp;
  const int frames = 24, every = 2;
  const std::vector<Camera> truth = room_path(frames);
  const std::string video = tmp / "room.avi";
  ASSERT_TRUE(write_room_video(video, truth)) << "OpenCV cannot write MJPG";
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
}  // namespace weathergs::capture
