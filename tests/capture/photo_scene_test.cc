// `weathergs photo-scene`: a photograph becomes a clear dataset whose views are crops of it, whose
// cameras pan about one centre, and whose synthetic depth is a ground plane seen from a level camera;
// the weather generator accepts it (lens drops and rain). Bad inputs fail clearly and leave nothing.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/error.h"
#include "core/image.h"
#include "core/json_reader.h"
#include "capture/photo_scene.h"
#include "generator/weather.h"
#include "tests/core/test_util.h"

namespace weathergs::capture {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// A textured 8-bit photograph (so a shifted crop is told apart from another).
std::string write_photo(const TempDir& tmp, int w, int h) {
  cv::Mat img(h, w, CV_8UC3);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img.at<cv::Vec3b>(y, x) = cv::Vec3b(uchar((x * 7 + y * 3) % 256), uchar((x * x / 5 + y) % 256), uchar((y * 11) % 256));
  const std::string path = tmp / "photo.png";
  EXPECT_TRUE(cv::imwrite(path, img));
  return path;
}

TEST(PhotoSceneTest, ViewsAreCropsOfAPanAndTheDepthIsAGroundPlane) {
  TempDir tmp;
  PhotoSceneOptions o;
  o.photo = write_photo(tmp, 640, 400);
  o.views = 9;
  o.width = 120;
  o.height = 80;
  const PhotoSceneSummary s = make_photo_scene(o, tmp / "ds");
  EXPECT_EQ(s.resized_height, 120);  // zoom 1.5 x 80
  EXPECT_EQ(s.resized_width, 192);   // 640 * 120 / 400
  const Dataset ds = read_dataset(tmp / "ds");
  ASSERT_EQ(ds.cameras.size(), 9u);
  EXPECT_EQ(ds.info.weather, "clear");
  EXPECT_EQ(ds.split("test"), (std::vector<std::string>{"000", "008"}));

  cv::Mat resized;
  cv::resize(cv::imread(o.photo), resized, cv::Size(192, 120), 0, 0, cv::INTER_AREA);
  const double fx = 4.0 / 6.0 * 120;  // the shipped camera: 4 mm lens, 6 mm sensor
  double last_yaw = -1e9;
  for (int i = 0; i < 9; ++i) {
    const Camera& c = ds.cameras[size_t(i)];
    EXPECT_DOUBLE_EQ(c.fx, fx);
    ASSERT_TRUE(c.f_number && c.focal_length_mm && c.focus_distance_m);
    EXPECT_NEAR((c.center_world() - Eigen::Vector3d(0, 0, 1.6)).norm(), 0, 1e-12) << "a pan about one centre";
    // Level camera: image down is world down; the yaw grows from view to view.
    EXPECT_NEAR(c.rotation().row(1).dot(Eigen::Vector3d(0, 0, -1)), 1, 1e-12);
    const Eigen::Vector3d fwd = c.rotation().row(2);
    const double yaw = std::atan2(fwd.x(), fwd.y());
    EXPECT_GT(yaw, last_yaw);
    last_yaw = yaw;
    // The view is the crop at x = i * (192 - 120) / 8 = 9 i, centred vertically (top 20).
    const cv::Mat view = cv::imread(ds.path(ImageKind::kImages, c.name));
    const cv::Mat crop = resized(cv::Rect(9 * i, 20, 120, 80));
    EXPECT_EQ(cv::norm(view, crop, cv::NORM_INF), 0) << "view " << c.name;
  }
  EXPECT_NEAR(s.pan_deg, (last_yaw - std::atan2(ds.cameras[0].rotation()(2, 0), ds.cameras[0].rotation()(2, 1))) * 180 / M_PI, 1e-9);

  // Depth: rows above the horizon are the backdrop; below, the ground plane z = h fy / (v + 0.5 - cy),
  // and that point lies on the ground (world z = 0) when unprojected.
  const Image depth = read_depth(ds.path(ImageKind::kDepth, "004"));
  ASSERT_EQ(depth.width, 120);
  EXPECT_FLOAT_EQ(depth.at(10, 5), 30.f);
  for (int v : {41, 50, 79}) {
    const double z = 1.6 * fx / (v + 0.5 - 40);
    EXPECT_NEAR(depth.at(60, v), std::min(30.0, z), 1e-4 * z);
    if (z < 30) {
      EXPECT_NEAR(ds.cameras[4].unproject({37.5, v + 0.5}, depth.at(37, v)).z(), 0, 1e-4) << "row " << v;
    }
  }

  // Deterministic: the same options give the same bytes.
  make_photo_scene(o, tmp / "again");
  for (const char* f : {"cameras.json", "images/003.png", "depth/003.exr"}) {
    std::ifstream a(tmp / ("ds/" + std::string(f)), std::ios::binary), b(tmp / ("again/" + std::string(f)), std::ios::binary);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(a), {}), std::string(std::istreambuf_iterator<char>(b), {})) << f;
  }
}

TEST(PhotoSceneTest, TheWeatherGeneratorAcceptsIt) {
  TempDir tmp;
  PhotoSceneOptions o;
  o.photo = write_photo(tmp, 400, 240);
  o.views = 4;
  o.width = 96;
  o.height = 64;
  make_photo_scene(o, tmp / "clear");
  const Json spec = Json::parse(R"({"seed": 3, "style": "paper", "effects": {
      "rain": {"intensity": "heavy"},
      "lens_droplets": {"count": 30, "radius_mm": [0.5, 1.5], "glass_distance_m": 0.015}}})");
  generator::WeatherRunOptions wo;
  wo.write_targets = true;
  generator::run_weather(tmp / "clear", JsonReader(spec, "spec.json"), tmp / "rain", wo);
  const Dataset ds = read_dataset(tmp / "rain");
  ASSERT_EQ(ds.cameras.size(), 4u);
  double drops = 0, changed = 0;
  for (const Camera& c : ds.cameras) {
    const Image mask = read_mask(ds.path(ImageKind::kLensMask, c.name));
    for (float m : mask.data) drops += m;
    const Image w = read_image(ds.path(ImageKind::kImages, c.name)), clean = read_image(ds.path(ImageKind::kClean, c.name));
    for (size_t k = 0; k < w.data.size(); ++k) changed += std::abs(w.data[k] - clean.data[k]) > 0.02f;
  }
  EXPECT_GT(drops / (4 * 96 * 64), 0.02) << "30 drops of 0.5-1.5 mm at 15 mm cover part of every view";
  EXPECT_GT(changed / (4 * 96 * 64 * 3), 0.05) << "heavy paper-style rain changes the views";
}

// Through the binary, as a user runs it.
TEST(PhotoSceneTest, TheCommandWritesADatasetAndRefusesBadInput) {
  TempDir tmp;
  const std::string photo = write_photo(tmp, 480, 320);
  auto run = [&](const std::string& args) {
    const int st = std::system((std::string(WEATHERGS_BINARY) + " --quiet photo-scene " + args + " > '" + (tmp / "p.log") +
                                "' 2>&1")
                                   .c_str());
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  };
  ASSERT_EQ(run("--photo " + photo + " --out " + (tmp / "ds") + " --views 5 --width 96 --height 64"), 0)
      << read_file(tmp / "p.log");
  const Dataset ds = read_dataset(tmp / "ds");
  EXPECT_EQ(ds.cameras.size(), 5u);
  EXPECT_EQ(ds.info.name, "ds");
  for (const Camera& c : ds.cameras) {
    EXPECT_EQ(read_image(ds.path(ImageKind::kImages, c.name)).width, 96);  // a clear dataset: images/
    EXPECT_TRUE(fs::exists(ds.path(ImageKind::kDepth, c.name)));
  }
  EXPECT_EQ(run("--photo " + (tmp / "none.png") + " --out " + (tmp / "ds2")), 2);
  EXPECT_NE(read_file(tmp / "p.log").find("none.png"), std::string::npos) << read_file(tmp / "p.log");
  EXPECT_EQ(run("--photo " + photo + " --out " + (tmp / "ds3") + " --zoom 0.5"), 2);
  EXPECT_NE(read_file(tmp / "p.log").find("zoom"), std::string::npos) << read_file(tmp / "p.log");
  EXPECT_FALSE(fs::exists(tmp / "ds2") || fs::exists(tmp / "ds3"));
}

TEST(PhotoSceneTest, BadInputsFailClearlyAndLeaveNothing) {
  TempDir tmp;
  PhotoSceneOptions o;
  o.photo = tmp / "missing.jpg";
  EXPECT_THROW(make_photo_scene(o, tmp / "out"), InputError);
  {
    std::ofstream(tmp / "text.jpg") << "not an image";
    o.photo = tmp / "text.jpg";
    try {
      make_photo_scene(o, tmp / "out");
      ADD_FAILURE() << "expected InputError";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("cannot decode"), std::string::npos) << e.what();
    }
  }
  o.photo = write_photo(tmp, 200, 400);  // portrait: 150 px wide at zoom 1.5 x 200, narrower than 300
  try {
    make_photo_scene(o, tmp / "out");
    ADD_FAILURE() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("narrower than one 300 px view"), std::string::npos) << e.what();
  }
  PhotoSceneOptions bad = o;
  bad.views = 2;
  EXPECT_THROW(make_photo_scene(bad, tmp / "out"), InputError);
  bad = o;
  bad.zoom = 0.5;
  EXPECT_THROW(make_photo_scene(bad, tmp / "out"), InputError);
  bad = o;
  bad.camera_height_m = std::nan("");
  EXPECT_THROW(make_photo_scene(bad, tmp / "out"), InputError);
  bad = o;
  bad.focus_distance_m = 0.001;
  EXPECT_THROW(make_photo_scene(bad, tmp / "out"), InputError);
  EXPECT_FALSE(fs::exists(tmp / "out"));
  for (const auto& e : fs::directory_iterator(tmp.path())) EXPECT_EQ(e.path().filename().string().rfind("out", 0), std::string::npos) << e.path();
}

}  // namespace
}  // namespace weathergs::capture
