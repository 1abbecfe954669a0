#include <gtest/gtest.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "core/camera.h"
#include "core/dataset.h"
#include "tests/core/test_util.h"

namespace weathergs {
namespace {

using testing::TempDir;

Camera make_camera(const std::string& name) {
  Camera c;
  c.name = name;
  c.width = 600;
  c.height = 400;
  c.fx = c.fy = 520;
  c.cx = 300;
  c.cy = 200;
  Eigen::Matrix3d r = Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  c.camera_from_world.topLeftCorner<3, 3>() = r;
  c.camera_from_world.topRightCorner<3, 1>() = Eigen::Vector3d(0.5, -1, 4);
  c.exposure_s = 1.0 / 60;
  return c;
}

TEST(CameraTest, ProjectionFollowsTheContract) {
  Camera c = make_camera("000");
  // A point on the optical axis projects to the principal point (pixel-corner origin).
  Eigen::Vector3d on_axis = c.world_from_camera().topLeftCorner<3, 3>() * Eigen::Vector3d(0, 0, 5) +
                            c.world_from_camera().topRightCorner<3, 1>();
  auto uv = c.project(on_axis);
  ASSERT_TRUE(uv);
  EXPECT_NEAR(uv->x(), 300, 1e-9);
  EXPECT_NEAR(uv->y(), 200, 1e-9);
  // u = fx x/z + cx for an explicit camera-space point.
  Eigen::Vector2d p = c.project_camera({1, -0.5, 2});
  EXPECT_NEAR(p.x(), 520 * 0.5 + 300, 1e-12);
  EXPECT_NEAR(p.y(), 520 * -0.25 + 200, 1e-12);
  // Unproject(project(p)) == p at the planar depth.
  Eigen::Vector3d pw(0.3, 0.7, 1.1);
  double z = c.to_camera(pw).z();
  Eigen::Vector3d back = c.unproject(*c.project(pw), z);
  EXPECT_LT((back - pw).norm(), 1e-12);
  // Behind the camera: no projection.
  Eigen::Vector3d behind = c.world_from_camera().topLeftCorner<3, 3>() * Eigen::Vector3d(0, 0, -1) +
                           c.world_from_camera().topRightCorner<3, 1>();
  EXPECT_FALSE(c.project(behind));
  // The center maps to the camera origin.
  EXPECT_LT(c.to_camera(c.center_world()).norm(), 1e-12);
}

TEST(CameraTest, ValidationNamesTheProblem) {
  Camera c = make_camera("a");
  EXPECT_NO_THROW(validate_camera(c, "x"));
  c.fx = -1;
  EXPECT_THROW(validate_camera(c, "x"), InputError);
  c = make_camera("a");
  c.camera_from_world(0, 0) = 2;
  EXPECT_THROW(validate_camera(c, "x"), InputError);
}

Dataset make_dataset(const std::string& root) {
  Dataset d;
  d.root = root;
  std::vector<std::string> names;
  for (int i = 0; i < 10; ++i) {
    char n[16];
    std::snprintf(n, sizeof n, "%03d", i);
    d.cameras.push_back(make_camera(n));
    names.push_back(n);
  }
  d.info.name = "toy_rain";
  d.info.scene = "toy";
  d.info.weather = "rain";
  d.info.splits = llff_splits(names);
  d.info.splits_rule = kLlffSplitRule;
  return d;
}

TEST(DatasetTest, LlffSplitHoldsOutEveryEighth) {
  auto s = llff_splits({"a", "b", "c", "d", "e", "f", "g", "h", "i", "j"});
  EXPECT_EQ(s["test"], (std::vector<std::string>{"a", "i"}));
  EXPECT_EQ(s["train"].size(), 8u);
}

TEST(DatasetTest, RoundTrip) {
  TempDir dir;
  Dataset d = make_dataset(dir.path());
  write_dataset(d);
  Dataset back = read_dataset(dir.path());
  EXPECT_EQ(back.info.name, "toy_rain");
  EXPECT_EQ(back.info.splits, d.info.splits);
  ASSERT_EQ(back.cameras.size(), 10u);
  EXPECT_LT((back.cameras[3].camera_from_world - d.cameras[3].camera_from_world).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(back.cameras[3].exposure_s, 1.0 / 60);
  EXPECT_EQ(back.path(ImageKind::kImages, "003"), dir.path() + "/images/003.png");
}

// Writes `text` as cameras.json next to a valid dataset.json and returns the error message.
std::string cameras_error(const std::string& text) {
  TempDir dir;
  write_dataset(make_dataset(dir.path()));
  write_file_atomic(dir / "cameras.json", text);
  try {
    read_dataset(dir.path());
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(DatasetTest, ErrorsNameFilePointerAndExpectation) {
  const std::string cam =
      R"({"name":"000","width":4,"height":4,"fx":1,"fy":1,"cx":2,"cy":2,)"
      R"("camera_from_world":[[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]])";
  std::string e = cameras_error(R"({"views":[)" + cam + R"(, "fxx": 3}]})");
  EXPECT_NE(e.find("cameras.json:/views/0"), std::string::npos) << e;
  EXPECT_NE(e.find("'fxx'"), std::string::npos) << e;

  e = cameras_error(R"({"views":[)" + cam + R"(, "time_s": "soon"}]})");
  EXPECT_NE(e.find("/views/0/time_s"), std::string::npos) << e;
  EXPECT_NE(e.find("expected a number"), std::string::npos) << e;

  e = cameras_error(R"({"views":[)");
  EXPECT_NE(e.find("malformed JSON"), std::string::npos) << e;

  e = cameras_error(R"({"views":[{"name":"000"}]})");
  EXPECT_NE(e.find("/views/0/width"), std::string::npos) << e;
  // Splits naming views that cameras.json lacks.
  e = cameras_error(R"({"views":[)" + cam + "}]}");
  EXPECT_NE(e.find("not in cameras.json"), std::string::npos) << e;
}

TEST(DatasetTest, UnknownTopLevelKeyInDatasetJson) {
  TempDir dir;
  write_dataset(make_dataset(dir.path()));
  Json j = read_json_file(dir / "dataset.json");
  j["splitz"] = Json::object();
  write_file_atomic(dir / "dataset.json", j.dump());
  try {
    read_dataset(dir.path());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'splitz'"), std::string::npos) << e.what();
  }
}

TEST(DatasetTest, UnsafeViewNamesRejected) {
  EXPECT_TRUE(is_safe_view_name("view_01.a-b"));
  EXPECT_FALSE(is_safe_view_name("../x"));
  EXPECT_FALSE(is_safe_view_name(".hidden"));
  EXPECT_FALSE(is_safe_view_name("a b"));
  EXPECT_FALSE(is_safe_view_name(""));
}

TEST(DatasetTest, NumberedViewNames) {
  EXPECT_EQ(numbered_view_name(7), "007");
  EXPECT_EQ(numbered_view_name(12, 5), "00012");
  EXPECT_EQ(numbered_view_name(1234), "1234");  // wider than the padding: all digits kept
  EXPECT_TRUE(is_safe_view_name(numbered_view_name(0)));
}

}  // namespace
}  // namespace weathergs

#include "core/colmap_model.h"

namespace weathergs {
namespace {

TEST(ColmapModelTest, TextRoundTripKeepsPoses) {
  TempDir dir;
  std::vector<Camera> cams = {make_camera("000"), make_camera("001")};
  cams[1].camera_from_world.topLeftCorner<3, 3>() =
      Eigen::AngleAxisd(3.0, Eigen::Vector3d(1, 0.3, -0.2).normalized()).toRotationMatrix();  // w < 0 case
  ColmapModel m = colmap_model_from_cameras(cams);
  ColmapPoint3D p;
  p.id = 5;
  p.xyz = {1, 2, 3};
  p.rgb = {255, 128, 0};
  p.error = 0.25;
  p.track = {{1, 0}, {2, 0}};
  m.points.push_back(p);
  m.images[0].points2d.emplace_back(10.5, 20.25, 5);
  write_colmap_text(dir.path(), m);
  ColmapModel back = read_colmap_text(dir.path());
  ASSERT_EQ(back.images.size(), 2u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_LT((back.images[i].camera_from_world - cams[i].camera_from_world).norm(), 1e-12);
    EXPECT_EQ(back.images[i].name, cams[i].name + ".png");
  }
  ASSERT_EQ(back.images[0].points2d.size(), 1u);
  EXPECT_TRUE(back.images[1].points2d.empty());
  ASSERT_EQ(back.points.size(), 1u);
  EXPECT_EQ(back.points[0].xyz, p.xyz);
  EXPECT_EQ(back.points[0].track, p.track);
  EXPECT_DOUBLE_EQ(back.cameras[1].fx, 520);
}

TEST(ColmapModelTest, MalformedLineNamesFileAndLine) {
  TempDir dir;
  write_file_atomic(dir / "points3D.txt", "# header\n1 0 0 0 255 255 255 0\n2 0 0 zero 1 1 1 0\n");
  try {
    read_colmap_points3d(dir / "points3D.txt");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("points3D.txt:3"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace weathergs
