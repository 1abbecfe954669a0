// `weathergs generate` end to end on the tiny profile: Blender -> weather -> COLMAP exports, the render
// cache, the CLI, and failures that leave nothing behind.
#include <gtest/gtest.h>

#include <algorithm>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "core/atomic_file.h"
#include "core/colmap_model.h"
#include "core/dataset.h"
#include "core/dataset_layout.h"
#include "core/image.h"
#include "capture/generate.h"
#include "capture/process.h"
#include "tests/core/test_util.h"

namespace weathergs::capture {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// cameras.json rotations come from Blender's float32 matrices (orthonormal to ~1e-7); COLMAP stores a
// unit quaternion, i.e. the nearest rotation. A convention error (axes, inverse) would be O(1).
constexpr double kPoseAgreement = 1e-6;
// The required bar for the exported model.
constexpr double kMaxReprojectionErrorPx = 1.0;

std::string scene_path(const std::string& name) { return std::string(WEATHERGS_SOURCE_DIR) + "/scenes/" + name; }

double mean_abs_diff(const Image& a, const Image& b) {
  double s = 0;
  for (size_t i = 0; i < a.data.size(); ++i) s += std::abs(a.data[i] - b.data[i]);
  return s / double(a.data.size());
}

// COLMAP reads the model, its reprojection error is small, and it agrees with cameras.json.
// min_points: the clean tiny views give > 20 points; the paper-style heavy rain with lens drops
// hides most features at 192x128 (12 points measured), so its model needs only a few.
void check_model(const std::string& model_dir, const std::vector<Camera>& cameras, const ColmapOptions& o,
                 int min_points) {
  const ModelStats s = analyze_model(model_dir, o, model_dir + "/../analyzer.log");
  EXPECT_EQ(s.registered_images, int(cameras.size()));
  EXPECT_GT(s.points, min_points) << model_dir;
  EXPECT_LT(s.mean_reprojection_error_px, kMaxReprojectionErrorPx) << model_dir;
  const ColmapModel m = read_colmap_text(model_dir);
  ASSERT_EQ(m.images.size(), cameras.size());
  std::map<int, ColmapCameraModel> cams;
  for (const auto& c : m.cameras) cams[c.id] = c;
  for (const ColmapImage& img : m.images) {
    const std::string view = fs::path(img.name).stem().string();
    const Camera* cam = nullptr;
    for (const Camera& c : cameras)
      if (c.name == view) cam = &c;
    ASSERT_NE(cam, nullptr) << img.name;
    EXPECT_LT((img.camera_from_world - cam->camera_from_world).cwiseAbs().maxCoeff(), kPoseAgreement) << view;
    const ColmapCameraModel& k = cams.at(img.camera_id);
    EXPECT_EQ(k.width, cam->width);
    EXPECT_EQ(k.height, cam->height);
    EXPECT_NEAR(k.fx, cam->fx, 1e-9);
    EXPECT_NEAR(k.cy, cam->cy, 1e-9);
  }
  // Every triangulated point lies in front of the cameras that observe it and reprojects near its
  // observation (our projection, not COLMAP's).
  std::map<int, const ColmapImage*> by_id;
  for (const auto& img : m.images) by_id[img.id] = &img;
  double worst = 0;
  for (const ColmapPoint3D& p : m.points)
    for (const auto& [iid, idx] : p.track) {
      const ColmapImage& img = *by_id.at(iid);
      const Camera* cam = nullptr;
      for (const Camera& c : cameras)
        if (c.name + ".png" == img.name) cam = &c;
      auto uv = cam->project(p.xyz);
      ASSERT_TRUE(uv.has_value());
      worst = std::max(worst, (*uv - img.points2d.at(size_t(idx)).head<2>()).norm());
    }
  EXPECT_LT(worst, 2.0) << "triangulation keeps observations within 2 px (Mapper.filter_max_reproj_error)";
}

bool have_blender_and_colmap() { return !find_executable("blender").empty() && !find_executable("colmap").empty(); }

// The tiny profile with its own Blender cache in tmp.
GenerateOptions tiny_options(const TempDir& tmp) {
  GenerateOptions o;
  o.blender.script = testing::blender_script();
  o.profile = "tiny";
  o.cache_dir = tmp / "cache";
  return o;
}

TEST(GenerateTest, TinyRainVariantEndToEnd) {
  if (!have_blender_and_colmap()) GTEST_SKIP() << "blender or colmap not installed";
  TempDir tmp;
  GenerateOptions o = tiny_options(tmp);
  const std::string out = tmp / "pool_rain";
  GenerateSummary s = generate_variant(scene_path("pool.json"), "rain", out, o);
  EXPECT_FALSE(s.cache_hit);
  EXPECT_EQ(s.views, 5);

  const Dataset ds = read_dataset(out);
  EXPECT_EQ(ds.info.name, "pool_rain");
  EXPECT_EQ(ds.info.scene, "pool");
  EXPECT_EQ(ds.info.weather, "rain");
  EXPECT_EQ(ds.split("test"), (std::vector<std::string>{"000"}));
  EXPECT_EQ(ds.split("train").size(), 4u);
  double diff = 0;
  for (const Camera& c : ds.cameras) {
    EXPECT_DOUBLE_EQ(c.exposure_s, 0.0167);
    const Image img = read_image(ds.path(ImageKind::kImages, c.name));
    const Image clean = read_image(ds.path(ImageKind::kClean, c.name));
    ASSERT_TRUE(img.same_shape(clean));
    EXPECT_EQ(img.width, 192);
    diff += mean_abs_diff(img, clean);
    const Image depth = read_depth(ds.path(ImageKind::kDepth, c.name));
    EXPECT_EQ(depth.width, 192);
  }
  EXPECT_GT(diff, 0.0) << "the weather pass changed nothing";
  check_model(out + "/sparse/0", ds.cameras, o.colmap_options, 4);
  check_model(out + "/sparse_clean/0", ds.cameras, o.colmap_options, 20);
  EXPECT_EQ(ds.info.generator->at("colmap").at("sparse").at("points").get<int>(), s.sparse.points);
  // One straight line through dataset.json's generator block: render, then weather, then COLMAP,
  // each stage's entries as it wrote them.
  const Json& gen = *ds.info.generator;
  std::vector<std::string> stage_names;
  for (const Json& st : gen.at("stages")) stage_names.push_back(st.at("name").get<std::string>());
  ASSERT_GE(stage_names.size(), 3u);
  EXPECT_EQ(stage_names.front(), "blender");
  EXPECT_EQ(stage_names.back(), "colmap");
  EXPECT_NE(std::find(stage_names.begin(), stage_names.end(), "rain"), stage_names.end());
  EXPECT_EQ(gen.at("profile"), "tiny");
  EXPECT_EQ(gen.at("variant"), "rain");
  EXPECT_TRUE(gen.contains("spec") && gen.contains("seed"));
  EXPECT_FALSE(gen.at("clean_render").at("cached").get<bool>());

  // transforms.json: OpenGL axes, so camera +z (backward) is minus our viewing direction.
  const Json tf = read_json_file(out + "/transforms.json");
  ASSERT_EQ(tf["frames"].size(), ds.cameras.size());
  const Camera& c0 = ds.cameras[0];
  const Json& f0 = tf["frames"][0];
  EXPECT_EQ(f0["file_path"], "images/000.png");
  const Eigen::Vector3d forward = c0.rotation().row(2).transpose();
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(f0["transform_matrix"][i][2].get<double>(), -forward[i], 1e-9);
    EXPECT_NEAR(f0["transform_matrix"][i][3].get<double>(), c0.center_world()[i], 1e-9);
  }

  // Another weather seed, through the CLI: the cached render is reused and the weather differs.
  const std::string out2 = tmp / "pool_rain_seed8";
  const std::string cmd = std::string(WEATHERGS_BINARY) + " --quiet generate --scene " + scene_path("pool.json") +
                          " --weather rain --profile tiny --seed 8 --cache " + o.cache_dir + " --out " + out2 +
                          " > " + (tmp / "cli.log") + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << read_file(tmp / "cli.log");
  EXPECT_NE(read_file(tmp / "cli.log").find("(cached)"), std::string::npos) << read_file(tmp / "cli.log");
  const Dataset ds2 = read_dataset(out2);
  EXPECT_EQ(ds2.info.generator->at("seed").get<int>(), 8);
  EXPECT_EQ(read_file(ds.path(ImageKind::kClean, "001")), read_file(ds2.path(ImageKind::kClean, "001")));
  EXPECT_NE(read_file(ds.path(ImageKind::kImages, "001")), read_file(ds2.path(ImageKind::kImages, "001")));

  // `weathergs triangulate` on a dataset without SfM points (as a user's own weathered dataset):
  // the train views' clean images -> sparse_clean/0; an existing model needs --force.
  const std::string bare = tmp / "bare";
  copy_tree(out, bare);
  fs::remove_all(bare + "/sparse");
  fs::remove_all(bare + "/sparse_clean");
  auto triangulate = [&](const std::string& args) {
    const std::string c = std::string(WEATHERGS_BINARY) + " --quiet triangulate --data " + bare + " " + args + " > " +
                          (tmp / "tri.log") + " 2>&1";
    return WEXITSTATUS(std::system(c.c_str()));
  };
  ASSERT_EQ(triangulate("--images clean --views train"), 0) << read_file(tmp / "tri.log");
  EXPECT_NE(read_file(tmp / "tri.log").find("sparse_clean/0"), std::string::npos) << read_file(tmp / "tri.log");
  const ColmapModel tri = read_colmap_text(bare + "/sparse_clean/0");
  EXPECT_GE(tri.points.size(), 20u);
  EXPECT_EQ(tri.images.size(), 4u);  // the train views only
  EXPECT_FALSE(fs::exists(bare + "/sparse/0"));
  EXPECT_EQ(triangulate("--images clean"), 2);
  EXPECT_NE(read_file(tmp / "tri.log").find("--force"), std::string::npos) << read_file(tmp / "tri.log");
  EXPECT_EQ(read_colmap_text(bare + "/sparse_clean/0").points.size(), tri.points.size());  // untouched

  // Bad input through the CLI: exit code 2, nothing written.
  const std::string bad = std::string(WEATHERGS_BINARY) + " --quiet generate --scene " + scene_path("pool.json") +
                          " --weather hail --profile tiny --cache " + o.cache_dir + " --out " + (tmp / "bad") +
                          " > " + (tmp / "bad.log") + " 2>&1";
  const int rc = std::system(bad.c_str());
  EXPECT_EQ(WEXITSTATUS(rc), 2);
  EXPECT_NE(read_file(tmp / "bad.log").find("no variant \"hail\""), std::string::npos);
  EXPECT_FALSE(fs::exists(tmp / "bad"));

  // COLMAP failing on the weathered views (the clean render comes from the cache, so Blender does
  // not run and the failure is COLMAP's own): no dataset is left, and the cache keeps its entry.
  GenerateOptions failing = o;
  failing.colmap_options.executable = "/bin/false";
  const int entries = testing::count_entries(o.cache_dir + "/clean");
  EXPECT_THROW(generate_variant(scene_path("pool.json"), "rain", tmp / "colmap_fails", failing), InputError);
  EXPECT_FALSE(fs::exists(tmp / "colmap_fails"));
  EXPECT_EQ(testing::count_entries(o.cache_dir + "/clean"), entries);
}

// Five 192x128 snowy views of pool share no feature COLMAP can triangulate, and COLMAP 3.8's
// point_triangulator then aborts in its final bundle adjustment (exit 134), which must not fail
// generate (`make demo` makes this variant). An empty triangulation is a result: the model keeps the
// known poses and has no points, and reconstruct falls back to its random initialization.
TEST(GenerateTest, TinySnowVariantGeneratesEvenWhenNothingTriangulates) {
  if (!have_blender_and_colmap()) GTEST_SKIP() << "blender or colmap not installed";
  TempDir tmp;
  const GenerateOptions o = tiny_options(tmp);
  const std::string out = tmp / "pool_snow";
  const GenerateSummary s = generate_variant(scene_path("pool.json"), "snow", out, o);
  EXPECT_EQ(s.views, 5);
  const Dataset ds = read_dataset(out);
  const ColmapModel m = read_colmap_text(ds.file(layout::kSparseModelDir));
  EXPECT_EQ(m.images.size(), 5u);  // the known poses, whatever was triangulated
  std::printf("tiny pool_snow: %zu points triangulated from the snowy views\n", m.points.size());
  check_model(ds.file(layout::kSparseCleanModelDir), ds.cameras, o.colmap_options, 20);
}

// A missing tool is found before any work: no dataset, no cache entry, an error naming the tool.
TEST(GenerateTest, MissingToolsStopGenerateBeforeAnyWork) {
  TempDir tmp;
  GenerateOptions o = tiny_options(tmp);
  o.colmap_options.executable = tmp / "no-colmap";
  try {
    generate_variant(scene_path("factory.json"), "clear", tmp / "out", o);
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("COLMAP not found"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(tmp / "out"));
  o.colmap = false;
  o.blender.executable = tmp / "no-blender";
  try {
    generate_variant(scene_path("factory.json"), "clear", tmp / "out", o);
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("Blender not found"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(tmp / "out"));
  EXPECT_FALSE(fs::exists(tmp / "cache/clean") && testing::count_entries(tmp / "cache/clean") > 0);
}

}  // namespace
}  // namespace weathergs::capture
