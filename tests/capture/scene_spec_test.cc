// Scene specs: every shipped scene parses, bad specs fail with their location, the camera path is
// forward-facing, and a missing or failing Blender leaves no partial dataset behind.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>

#include "core/atomic_file.h"
#include "core/error.h"
#include "capture/blender.h"
#include "capture/process.h"
#include "capture/scene_spec.h"
#include "tests/core/test_util.h"

namespace weathergs::capture {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

std::string scene_path(const std::string& name) { return std::string(WEATHERGS_SOURCE_DIR) + "/scenes/" + name; }

// Writes `scene` (a shipped spec modified by `edit`) to a temporary file.
std::string write_modified(const TempDir& tmp, const std::string& scene, const std::function<void(Json&)>& edit) {
  Json j = read_json_file(scene_path(scene));
  edit(j);
  const std::string path = tmp / ("spec_" + scene);
  write_file_atomic(path, j.dump(1));
  return path;
}

// Expects an InputError whose message contains `needle`.
template <typename F>
void expect_input_error(F&& f, const std::string& needle) {
  try {
    f();
    ADD_FAILURE() << "expected an InputError containing \"" << needle << "\"";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(SceneSpecTest, ShippedScenesParse) {
  for (const char* name : {"tanabata.json", "factory.json", "pool.json"}) {
    SceneSpec s = read_scene_spec(scene_path(name));
    EXPECT_EQ(s.variants.size(), 2u) << name;
    EXPECT_TRUE(s.variants.count("snow") && s.variants.count("rain")) << name;
    EXPECT_EQ(s.variant("snow").surface["kind"], "snow");
    EXPECT_EQ(s.variant("rain").surface["kind"], "rain");
    EXPECT_EQ(s.variant("clear").surface["kind"], "clear");
    EXPECT_TRUE(s.variant("rain").weather.is_object());
    for (const char* p : {"tiny", "quick", "paper"}) EXPECT_NO_THROW(s.profile(p)) << name << " " << p;
    EXPECT_EQ(s.profile("paper").width, 600);
    EXPECT_EQ(s.profile("paper").height, 400);
    EXPECT_EQ(s.profile("paper").views, 34);
    // Variant lights override only what they name.
    EXPECT_EQ(s.variant("snow").lights["sun"]["elevation_deg"], s.lights["sun"]["elevation_deg"]);
    EXPECT_NE(s.variant("snow").lights["sun"]["strength"], s.lights["sun"]["strength"]);
  }
}

TEST(SceneSpecTest, SceneTypesAreTheBlenderLayoutModules) {
  // One list: the modules of blender_scripts/weathergs_blender/layouts/ (generated at build time).
  std::vector<std::string> modules;
  for (const auto& e : std::filesystem::directory_iterator(std::string(WEATHERGS_SOURCE_DIR) +
                                                           "/blender_scripts/weathergs_blender/layouts"))
    if (e.path().extension() == ".py" && e.path().stem().string()[0] != '_') modules.push_back(e.path().stem().string());
  std::sort(modules.begin(), modules.end());
  EXPECT_EQ(scene_types(), modules);
  for (const char* name : {"tanabata.json", "factory.json", "pool.json"}) {
    const SceneSpec s = read_scene_spec(scene_path(name));
    EXPECT_NE(std::find(modules.begin(), modules.end(), s.type), modules.end()) << name;
  }
}

// The restoration's training scenes (scripts/make-training-data.sh renders each one clear and as its
// overcast `wet` and `snowy` variants): every file parses, has a layout module and both variants.
TEST(SceneSpecTest, TrainingScenesParseWithTheirOvercastVariants) {
  const std::vector<std::string> types = scene_types();
  int count = 0;
  for (const auto& e : std::filesystem::directory_iterator(scene_path("training"))) {
    if (e.path().extension() != ".json") continue;
    ++count;
    const std::string name = e.path().filename().string();
    const SceneSpec s = read_scene_spec(e.path().string());
    EXPECT_EQ(s.type, e.path().stem().string()) << name;
    EXPECT_NE(std::find(types.begin(), types.end(), s.type), types.end()) << name;
    EXPECT_EQ(s.variant("wet").surface["kind"], "rain") << name;
    EXPECT_EQ(s.variant("snowy").surface["kind"], "snow") << name;
    EXPECT_NO_THROW(s.profile("quick")) << name;
    for (const char* benchmark : {"tanabata", "factory", "pool"}) EXPECT_NE(s.type, benchmark) << name;
  }
  EXPECT_EQ(count, 6);  // park, parking_lot, harbour, market, station, village
}

// The randomized training scenes (scripts/make-assorted-scenes.py, ASSORTED_SCENES in
// make-training-data.sh): every drawn spec parses with both variants and a distinct-view quick path,
// the draw is a function of (seed, index) alone, and different indices draw different scenes.
TEST(SceneSpecTest, AssortedScenesParseAndAreDeterministic) {
  TempDir tmp;
  auto draw = [&](const std::string& dir, int n, int seed) {
    const std::string cmd = "/usr/bin/python3 " + std::string(WEATHERGS_SOURCE_DIR) + "/scripts/make-assorted-scenes.py " +
                            std::to_string(n) + " " + (tmp / dir) + " " + std::to_string(seed) + " > /dev/null 2>&1";
    return WEXITSTATUS(std::system(cmd.c_str()));
  };
  auto at = [&](const char* dir, const char* file) { return tmp / (std::string(dir) + "/" + file); };
  ASSERT_EQ(draw("a", 12, 1), 0);
  ASSERT_EQ(draw("b", 3, 1), 0);  // fewer scenes: the first ones are the same
  ASSERT_EQ(draw("c", 3, 2), 0);  // another seed: other scenes
  std::set<uint64_t> layout_seeds;
  for (int i = 0; i < 12; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "assorted_%02d.json", i);
    const SceneSpec s = read_scene_spec(at("a", name));
    EXPECT_EQ(s.type, "assorted");
    EXPECT_EQ(s.variant("wet").surface["kind"], "rain") << name;
    EXPECT_EQ(s.variant("snowy").surface["kind"], "snow") << name;
    const std::vector<Camera> cams = scene_cameras(s, s.profile("quick"));
    EXPECT_GE(min_camera_separation_fraction(cams), kMinCameraSeparationFraction) << name;
    layout_seeds.insert(s.seed);
    if (i < 3) {
      EXPECT_EQ(read_file(at("a", name)), read_file(at("b", name))) << name;
      EXPECT_NE(read_file(at("a", name)), read_file(at("c", name))) << name;
    }
  }
  EXPECT_EQ(layout_seeds.size(), 12u);
  EXPECT_NE(draw("bad", 0, 1), 0);  // N outside 1..100 is refused
}

TEST(SceneSpecTest, EveryProfileHasDistinctViewsAndTestViewsBetweenTrainingViews) {
  for (const char* name : {"tanabata.json", "factory.json", "pool.json"}) {
    const SceneSpec s = read_scene_spec(scene_path(name));
    for (const auto& [pname, profile] : s.profiles) {
      const std::vector<Camera> cams = scene_cameras(s, profile);
      EXPECT_GE(min_camera_separation_fraction(cams), kMinCameraSeparationFraction) << name << " " << pname;
      // LLFF every-8th: each test view's nearest camera is a training view, never another test view.
      for (size_t i = 0; i < cams.size(); i += size_t(s.split_every)) {
        size_t nearest = i;
        double best = 1e300;
        for (size_t j = 0; j < cams.size(); ++j)
          if (j != i) {
            const double d = (cams[i].center_world() - cams[j].center_world()).norm();
            if (d < best) best = d, nearest = j;
          }
        EXPECT_NE(nearest % size_t(s.split_every), 0u) << name << " " << pname << " view " << i;
        EXPECT_GT(best, 0.0);
      }
    }
  }
}

TEST(SceneSpecTest, CameraPathIsForwardFacing) {
  SceneSpec s = read_scene_spec(scene_path("pool.json"));
  const ProfileSpec& p = s.profile("paper");
  std::vector<Camera> cams = scene_cameras(s, p);
  ASSERT_EQ(int(cams.size()), p.views);
  for (const Camera& c : cams) {
    validate_camera(c, c.name);
    // The target projects to the principal point; the horizon stays level (camera x horizontal).
    auto uv = c.project(s.camera.look_at_m);
    ASSERT_TRUE(uv.has_value());
    EXPECT_NEAR(uv->x(), c.cx, 1e-9);
    EXPECT_NEAR(uv->y(), c.cy, 1e-9);
    EXPECT_NEAR(c.rotation().row(0).z(), 0.0, 1e-12);
    EXPECT_LT(c.rotation().row(1).z(), 0.0);  // image y points down in the world
    EXPECT_NEAR(c.fx, s.camera.focal_length_mm / s.camera.sensor_width_mm * p.width, 1e-9);
    EXPECT_LT((c.center_world() - s.camera.position_m).norm(),
              s.camera.radius_m.norm() + s.camera.depth_m + 1e-9);
  }
  EXPECT_EQ(cams[3].name, "003");
  EXPECT_DOUBLE_EQ(cams[3].time_s, 3 * s.camera.frame_interval_s);
  // Views are spread out: a real baseline for triangulation.
  EXPECT_GT((cams[0].center_world() - cams[p.views / 4].center_world()).norm(), 0.5);
}

TEST(SceneSpecTest, BadSpecsNameTheirLocation) {
  TempDir tmp;
  expect_input_error([&] { read_scene_spec(tmp / "missing.json"); }, "not found");
  expect_input_error([&] { read_scene_spec(write_modified(tmp, "pool.json", [](Json& j) { j["colour"] = 1; })); },
                     "unknown key(s) 'colour'");
  expect_input_error(
      [&] { read_scene_spec(write_modified(tmp, "pool.json", [](Json& j) { j["camera"]["focal_length_mm"] = "24"; })); },
      "/camera/focal_length_mm: expected a number");
  expect_input_error(
      [&] { read_scene_spec(write_modified(tmp, "pool.json", [](Json& j) { j["profiles"]["quick"]["height"] = 400; })); },
      "width >= height");
  expect_input_error(
      [&] { read_scene_spec(write_modified(tmp, "pool.json", [](Json& j) { j["variants"]["snow"]["surface"]["kind"] = "hail"; })); },
      "/variants/snow/surface/kind");
  expect_input_error(
      [&] { read_scene_spec(write_modified(tmp, "pool.json", [](Json& j) { j["variants"]["rain"]["lights"]["sun"]["strenght"] = 1; })); },
      "/variants/rain/lights/sun: unknown key(s) 'strenght'");
  expect_input_error(
      [&] { read_scene_spec(write_modified(tmp, "pool.json", [](Json& j) { j["type"] = "castle"; })); },
      "unknown scene type");
  expect_input_error(
      [&] { read_scene_spec(write_modified(tmp, "pool.json", [](Json& j) { j["camera"]["look_at_m"] = j["camera"]["position_m"]; })); },
      "must differ");
  // A two-turn path without the dolly revisits its poses: rejected before anything renders.
  expect_input_error(
      [&] { read_scene_spec(write_modified(tmp, "pool.json", [](Json& j) { j["camera"]["depth_m"] = 0.0; })); },
      "views closer than");
  SceneSpec s = read_scene_spec(scene_path("pool.json"));
  expect_input_error([&] { s.profile("huge"); }, "no profile \"huge\"");
  expect_input_error([&] { s.variant("hail"); }, "no variant \"hail\"");
}

TEST(SceneSpecTest, MissingBlenderLeavesNothing) {
  TempDir tmp;
  SceneSpec s = read_scene_spec(scene_path("pool.json"));
  BlenderOptions options;
  options.script = testing::blender_script();
  options.executable = tmp / "no-such-blender";
  expect_input_error([&] { render_clean_dataset(s, "rain", "tiny", tmp / "out", options); }, "cannot run");
  EXPECT_EQ(testing::count_entries(tmp.path()), 0);
  // A "Blender" that fails: a script exiting 1.
  const std::string fake = tmp / "fake-blender";
  {
    std::ofstream f(fake);
    f << "#!/bin/sh\necho 'Error: EEVEE exploded' >&2\nexit 1\n";
  }
  fs::permissions(fake, fs::perms::owner_all);
  options.executable = fake;
  expect_input_error([&] { render_clean_dataset(s, "rain", "tiny", tmp / "out", options); }, "EEVEE exploded");
  EXPECT_FALSE(fs::exists(tmp / "out"));
  EXPECT_EQ(testing::count_entries(tmp.path()), 1);  // only the fake
}

TEST(SceneSpecTest, ThreadCapReachesBlenderAndLlvmpipe) {
  TempDir tmp;
  BlenderOptions options;
  options.script = testing::blender_script();
  // A "Blender" that prints how it was called and fails, so the error carries its log.
  const std::string fake = tmp / "fake-blender";
  {
    std::ofstream f(fake);
    f << "#!/bin/sh\necho \"args: $*\" >&2\necho \"LP_NUM_THREADS=${LP_NUM_THREADS:-unset}\" >&2\nexit 1\n";
  }
  fs::permissions(fake, fs::perms::owner_all);
  options.executable = fake;
  // Cycles (the benchmark scenes): one-thread processes side by side, whatever the cap, each with a
  // job of its own views.
  SceneSpec cycles = read_scene_spec(scene_path("pool.json"));
  ASSERT_EQ(cycles.profile("tiny").engine, "cycles");
  for (int threads : {1, 2, 0}) {
    options.threads = threads;
    expect_input_error([&] { render_clean_dataset(cycles, "rain", "tiny", tmp / "out", options); },
                       "args: -b --factory-startup -t 1 --python-exit-code 1 --python");
  }
  options.threads = 2;
  expect_input_error([&] { render_clean_dataset(cycles, "rain", "tiny", tmp / "out", options); }, "blender_job_0.json");
  options.threads = 1;
  expect_input_error([&] { render_clean_dataset(cycles, "rain", "tiny", tmp / "out", options); }, "blender_job.json");
  // EEVEE: one process with the cap, and llvmpipe's.
  SceneSpec eevee = read_scene_spec(write_modified(tmp, "pool.json", [](Json& j) { j["profiles"]["tiny"]["engine"] = "eevee"; }));
  options.threads = 2;
  expect_input_error([&] { render_clean_dataset(eevee, "rain", "tiny", tmp / "out", options); },
                     "args: -b --factory-startup -t 2 --python-exit-code 1 --python");
  expect_input_error([&] { render_clean_dataset(eevee, "rain", "tiny", tmp / "out", options); }, "LP_NUM_THREADS=2");
  options.threads = 0;  // all cores: Blender's and llvmpipe's defaults
  expect_input_error([&] { render_clean_dataset(eevee, "rain", "tiny", tmp / "out", options); },
                     "args: -b --factory-startup --python-exit-code 1 --python");
  if (!std::getenv("LP_NUM_THREADS"))
    expect_input_error([&] { render_clean_dataset(eevee, "rain", "tiny", tmp / "out", options); }, "LP_NUM_THREADS=unset");
  options.threads = -1;
  expect_input_error([&] { render_clean_dataset(cycles, "rain", "tiny", tmp / "out", options); }, "threads is -1");
  EXPECT_FALSE(fs::exists(tmp / "out"));
}

TEST(SceneSpecTest, LayoutAndMaterialErrorsComeBackFromBlender) {
  if (find_executable("blender").empty()) GTEST_SKIP() << "blender not installed";
  TempDir tmp;
  BlenderOptions options;
  options.script = testing::blender_script();
  SceneSpec s = read_scene_spec(
      write_modified(tmp, "factory.json", [](Json& j) { j["layout"]["barrel_cuont"] = 3; }));
  expect_input_error([&] { render_clean_dataset(s, "snow", "tiny", tmp / "out", options); }, "/layout/barrel_cuont");
  EXPECT_FALSE(fs::exists(tmp / "out"));
  s = read_scene_spec(write_modified(tmp, "factory.json", [](Json& j) { j["materials"]["brick"]["scale_m"] = "big"; }));
  expect_input_error([&] { render_clean_dataset(s, "snow", "tiny", tmp / "out", options); },
                     "/materials/brick/scale_m: expected a number");
  s = read_scene_spec(write_modified(tmp, "factory.json", [](Json& j) { j["materials"].erase("barrel"); }));
  expect_input_error([&] { render_clean_dataset(s, "snow", "tiny", tmp / "out", options); }, "\"barrel\"");
  EXPECT_FALSE(fs::exists(tmp / "out"));
}

}  // namespace
}  // namespace weathergs::capture
