// `weathergs weather` end to end on synthetic clean datasets: outputs, "only what the scene calls
// for", determinism, hard cases, errors, and the CLI.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/parallel.h"
#include "generator/physics.h"
#include "generator/weather.h"
#include "tests/core/test_util.h"
#include "tests/generator/test_scene.h"

namespace weathergs::generator {
namespace {

namespace fs = std::filesystem;
using testing::SceneOptions;
using testing::TempDir;

Json run(const std::string& in, const Json& spec, const std::string& out, WeatherRunOptions o = {}) {
  return run_weather(in, JsonReader(spec, "spec.json"), out, o);
}

Json rain_spec(double rate = 25, Json extra = Json::object()) {
  Json spec = {{"seed", 7}, {"effects", {{"rain", {{"rate_mm_h", rate}, {"wind_m_s", {1.0, 0.5, 0.0}}}}}}};
  for (auto& [k, v] : extra.items()) spec[k] = v;
  return spec;
}

std::vector<std::string> stage_names(const Json& block) {
  std::vector<std::string> n;
  for (const Json& s : block["stages"]) n.push_back(s["name"]);
  return n;
}

// Every file under root, relative path -> bytes.
std::map<std::string, std::string> snapshot(const std::string& root) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(root))
    if (e.is_regular_file()) files[fs::relative(e.path(), root).string()] = read_file(e.path().string());
  return files;
}

// dataset.json without the measured seconds.
std::string without_seconds(const std::string& dataset_json) {
  Json j = Json::parse(dataset_json);
  for (Json& s : j["generator"]["stages"]) s.erase("seconds");
  return j.dump();
}

TEST(Weather, RainWritesACompleteDataset) {
  TempDir tmp;
  testing::make_clean_dataset(tmp / "clean", SceneOptions{});
  const Json block = run(tmp / "clean", rain_spec(), tmp / "out");
  EXPECT_EQ(stage_names(block), std::vector<std::string>{"rain"});
  const Dataset d = read_dataset(tmp / "out");
  EXPECT_EQ(d.info.weather, "rain");
  EXPECT_EQ(d.info.generator->at("seed"), 7);
  // The resolved spec has every default filled in.
  const Json& spec = block["spec"];
  EXPECT_EQ(spec["render"]["streak"], "analytic");
  EXPECT_EQ(spec["effects"]["rain"]["diameter_range_mm"][1], 6.0);
  EXPECT_NEAR(spec["effects"]["rain"]["turbulence"]["rms_m_s"].get<double>(), 0.25 * std::sqrt(1.25), 1e-12);
  for (const Camera& c : d.cameras) {
    for (const std::string& f : {d.path(ImageKind::kImages, c.name), d.path(ImageKind::kClean, c.name), d.path(ImageKind::kDepth, c.name),
                                 d.path(ImageKind::kParticleMask, c.name), d.layer_path("particle_alpha", c.name, ".exr"),
                                 d.layer_path("rain_alpha", c.name, ".exr"),
                                 d.layer_path("particles_rain", c.name, ".csv")})
      EXPECT_TRUE(fs::exists(f)) << f;
    const Image alpha = read_image(d.layer_path("particle_alpha", c.name, ".exr"));
    double sum = 0;
    for (float a : alpha.data) {
      ASSERT_TRUE(a >= 0 && a <= 1);
      sum += a;
    }
    EXPECT_GT(sum, 0) << c.name;
  }
  EXPECT_GT(block["counters"]["rain.particles_drawn"].get<int64_t>(), 0);
  EXPECT_NE(read_file(d.path(ImageKind::kImages, "000")), read_file(d.path(ImageKind::kClean, "000")));
}

TEST(Weather, ManifestRecordsThePhysics) {
  // No wind, no turbulence: every drop falls at exactly the Atlas speed of its diameter.
  TempDir tmp;
  testing::make_clean_dataset(tmp / "clean", SceneOptions{});
  Json spec = rain_spec(25, {{"render", {{"visibility_cutoff", 0.002}}}});  // more rows
  spec["effects"]["rain"]["wind_m_s"] = {0, 0, 0};
  run(tmp / "clean", spec, tmp / "out");
  std::istringstream csv(read_file(tmp / "out/layers/particles_rain/001.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line + "\n", "id,diameter_mm,visual_diameter_mm,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,camera_z_m,visible\n");
  int rows = 0, visible = 0;
  while (std::getline(csv, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    ASSERT_EQ(f.size(), 11u);
    const double d = std::stod(f[1]);
    EXPECT_GE(d, 0.1);
    EXPECT_LE(d, 6.0);
    // %.6g in the manifest: 6 significant digits.
    EXPECT_NEAR(std::stod(f[8]), -physics::atlas_velocity_m_s(d), 1e-4);
    EXPECT_EQ(std::stod(f[6]), 0.0);
    visible += std::stoi(f[10]);
    ++rows;
  }
  EXPECT_GT(rows, 10);
  EXPECT_GT(visible, 0);
}

TEST(Weather, OneParticleStateForAllViews) {
  // Two views at the same time share particles: the same id has the same position and velocity.
  TempDir tmp;
  SceneOptions o;
  o.time_step_s = 0;
  testing::make_clean_dataset(tmp / "clean", o);
  run(tmp / "clean", rain_spec(50, {{"render", {{"visibility_cutoff", 0.001}}}}), tmp / "out");
  auto rows = [&](const std::string& view) {
    std::map<std::string, std::string> m;
    std::istringstream csv(read_file(tmp / ("out/layers/particles_rain/" + view + ".csv")));
    std::string line;
    std::getline(csv, line);
    while (std::getline(csv, line)) {
      const size_t comma = line.find(',');
      // id -> diameter..velocity (columns 1..8); camera z and visibility are per view.
      std::string rest = line.substr(comma + 1);
      for (int i = 0; i < 2; ++i) rest = rest.substr(0, rest.rfind(','));
      m[line.substr(0, comma)] = rest;
    }
    return m;
  };
  const auto a = rows("000"), b = rows("001");
  int shared = 0;
  for (const auto& [id, values] : a) {
    auto it = b.find(id);
    if (it == b.end()) continue;
    EXPECT_EQ(values, it->second) << id;
    ++shared;
  }
  EXPECT_GT(shared, 5);
}

TEST(Weather, OnlyWhatTheSpecCallsFor) {
  TempDir tmp;
  testing::make_clean_dataset(tmp / "clean", SceneOptions{});
  // Fog only: no particle code, no particle outputs.
  const Json fog = run(tmp / "clean", {{"effects", {{"fog", {{"visibility_m", 50}}}}}}, tmp / "fog");
  EXPECT_EQ(stage_names(fog), std::vector<std::string>{"fog"});
  EXPECT_TRUE(fog["counters"].empty());
  EXPECT_FALSE(fs::exists(tmp / "fog/masks/particles"));
  EXPECT_FALSE(fs::exists(tmp / "fog/layers/particle_alpha"));
  EXPECT_TRUE(fs::exists(tmp / "fog/layers/fog_transmittance/000.exr"));
  EXPECT_EQ(read_dataset(tmp / "fog").info.weather, "fog");
  // Rain only: nothing of snow.
  const Json rain = run(tmp / "clean", rain_spec(), tmp / "rain");
  for (const auto& [k, v] : rain["counters"].items()) EXPECT_EQ(k.rfind("rain.", 0), 0u) << k;
  EXPECT_FALSE(fs::exists(tmp / "rain/layers/snow_alpha"));
  // All three: in pipeline order.
  Json all = rain_spec();
  all["effects"]["snow"] = {{"rate_mm_h", 2.5}};
  all["effects"]["fog"] = {{"from_rain", true}};
  const Json block = run(tmp / "clean", all, tmp / "all");
  EXPECT_EQ(stage_names(block), (std::vector<std::string>{"fog", "rain", "snow"}));
  EXPECT_EQ(read_dataset(tmp / "all").info.weather, "rain+snow+fog");
  EXPECT_NEAR(block["spec"]["effects"]["fog"]["resolved_beta_per_m"].get<double>(),
              physics::rain_extinction_per_m(25), 1e-15);
}

TEST(Weather, ZeroRateGivesTheCleanImages) {
  TempDir tmp;
  testing::make_clean_dataset(tmp / "clean", SceneOptions{});
  Json spec = rain_spec(0);
  spec["effects"]["snow"] = {{"rate_mm_h", 0}};
  const Json block = run(tmp / "clean", spec, tmp / "out");
  EXPECT_EQ(stage_names(block), (std::vector<std::string>{"rain", "snow"}));
  for (const std::string v : {"000", "001", "002"}) {
    const Image a = read_image(tmp / ("out/images/" + v + ".png")), b = read_image(tmp / ("clean/clean/" + v + ".png"));
    EXPECT_EQ(a.data, b.data) << v;
  }
}

TEST(Weather, DeterministicAcrossThreadsAndViewOrder) {
  TempDir tmp;
  SceneOptions o;
  o.views = 4;
  o.thin_lens = true;
  testing::make_clean_dataset(tmp / "clean", o);
  Json spec = rain_spec(40);
  spec["effects"]["snow"] = {{"rate_mm_h", 3}, {"wind_m_s", {2, 0, 0}}};
  spec["effects"]["fog"] = {{"visibility_m", 300}};
  const int threads = num_threads();
  set_num_threads(1);
  run(tmp / "clean", spec, tmp / "a");
  set_num_threads(2);
  WeatherRunOptions reversed;
  reversed.view_order = {"003", "001", "002", "000"};
  run(tmp / "clean", spec, tmp / "b", reversed);
  set_num_threads(threads);
  auto a = snapshot(tmp / "a"), b = snapshot(tmp / "b");
  ASSERT_EQ(a.size(), b.size());
  for (auto& [path, bytes] : a) {
    ASSERT_TRUE(b.count(path)) << path;
    if (path == "dataset.json") EXPECT_EQ(without_seconds(bytes), without_seconds(b[path]));
    else EXPECT_TRUE(bytes == b[path]) << path;
  }
}

TEST(Weather, HardCasesStayFiniteAndBounded) {
  struct Case {
    std::string name;
    SceneOptions scene;
    Json spec;
  };
  SceneOptions inf, big, half, one, exposure0, exposure1;
  big.background_depth = 1e10f;
  half.background_depth = 65504.0f;
  one.width = one.height = 1;
  one.fx = 1;
  Json heavy = rain_spec(500);
  Json gale = rain_spec(25);
  gale["effects"]["rain"]["wind_m_s"] = {60, 0, 0};
  gale["effects"]["snow"] = {{"rate_mm_h", 5}, {"wind_m_s", {60, 0, 0}}};
  Json e0 = rain_spec(25, {{"camera", {{"exposure_s", 0.0}}}});
  Json e1 = rain_spec(25, {{"camera", {{"exposure_s", 1.0}}}});
  Json fog = rain_spec(25);
  fog["effects"]["fog"] = {{"visibility_m", 100}};
  const std::vector<Case> cases = {{"rate500", inf, heavy},   {"wind60", inf, gale},   {"exposure0", inf, e0},
                                   {"exposure1", inf, e1},    {"bg1e10", big, fog},     {"bg65504", half, fog},
                                   {"bginf", inf, fog},       {"onepixel", one, fog}};
  for (const Case& c : cases) {
    TempDir tmp;
    testing::make_clean_dataset(tmp / "clean", c.scene);
    Json block;
    ASSERT_NO_THROW(block = run(tmp / "clean", c.spec, tmp / "out")) << c.name;
    for (const auto& e : fs::recursive_directory_iterator(tmp / "out/layers"))
      if (e.path().extension() == ".exr") {
        const Image img = read_image(e.path().string());
        for (float v : img.data) ASSERT_TRUE(std::isfinite(v) && v >= 0 && v <= 1) << c.name << " " << e.path();
      }
  }
  // Bounded memory: the peak resident size of this whole test process stays far below the machine's
  // (these cases used ~0.2 GB when written; 2 GB would mean the population escaped its bounds).
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmHWM:", 0) == 0) {
      EXPECT_LT(std::stol(line.substr(6)), 2L * 1024 * 1024) << line;  // kB
    }
  }
}

TEST(Weather, ErrorsNameTheSpecLocation) {
  TempDir tmp;
  testing::make_clean_dataset(tmp / "clean", SceneOptions{});
  auto message = [&](const Json& spec) {
    try {
      run(tmp / "clean", spec, tmp / "out");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message({{"effects", {{"lens_droplets", {{"count", 60}, {"cuont", 1}}}}}}).find("/effects/lens_droplets"),
            std::string::npos);
  EXPECT_NE(message({{"effects", {{"rain", {{"rate_mm_h", 5}, {"rate", 3}}}}}}).find("spec.json:/effects/rain"),
            std::string::npos);
  EXPECT_NE(message({{"effects", {{"rain", {{"rate_mm_h", -1}}}}}}).find("rate_mm_h"), std::string::npos);
  EXPECT_NE(message({{"effects", {{"fog", {{"visibility_m", 5}, {"beta_per_m", 1}}}}}}).find("exactly one"),
            std::string::npos);
  EXPECT_NE(message({{"effectz", Json::object()}}).find("effects"), std::string::npos);
  EXPECT_FALSE(fs::exists(tmp / "out"));  // failed runs leave nothing
  fs::remove(tmp / "clean/depth/001.exr");
  EXPECT_NE(message(rain_spec()).find("depth"), std::string::npos);
  EXPECT_FALSE(fs::exists(tmp / "out"));
}

TEST(Weather, RunOptionsAreValidated) {
  TempDir tmp;
  testing::make_clean_dataset(tmp / "clean", SceneOptions{});
  WeatherRunOptions bad_threshold;
  bad_threshold.mask_threshold = 0;
  EXPECT_THROW(run(tmp / "clean", rain_spec(), tmp / "out", bad_threshold), InputError);
  WeatherRunOptions unknown_view;
  unknown_view.view_order = {"000", "001", "007"};
  EXPECT_THROW(run(tmp / "clean", rain_spec(), tmp / "out", unknown_view), InputError);
  WeatherRunOptions missing_view;
  missing_view.view_order = {"000", "001"};
  EXPECT_THROW(run(tmp / "clean", rain_spec(), tmp / "out", missing_view), InputError);
  // A focus distance inside the focal length cannot be imaged.
  EXPECT_THROW(run(tmp / "clean", rain_spec(25, {{"camera", {{"f_number", 2.0}, {"focal_length_mm", 50.0},
                                                               {"focus_distance_m", 0.01}}}}),
                   tmp / "out"),
               InputError);
  EXPECT_FALSE(fs::exists(tmp / "out"));
}

TEST(Weather, EmbeddedSpecReportsItsPointer) {
  TempDir tmp;
  testing::make_clean_dataset(tmp / "clean", SceneOptions{});
  const Json scene = {{"variants", {{{"weather", {{"effects", {{"rain", {{"rate_mm_h", "heavy"}}}}}}}}}}};
  const JsonReader r(scene["variants"][0]["weather"], "scene.json", "/variants/0/weather");
  try {
    run_weather(tmp / "clean", r, tmp / "out", {});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("scene.json:/variants/0/weather/effects/rain/rate_mm_h"), std::string::npos)
        << e.what();
  }
}

TEST(Weather, CommandLine) {
  TempDir tmp;
  testing::make_clean_dataset(tmp / "clean", SceneOptions{});
  write_file_atomic(tmp / "spec.json", rain_spec(10).dump());
  const std::string bin = WEATHERGS_BINARY;
  const std::string cmd = bin + " --quiet weather --in " + (tmp / "clean") + " --spec " + (tmp / "spec.json") +
                          " --out " + (tmp / "out") + " --seed 3";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  EXPECT_EQ(read_dataset(tmp / "out").info.generator->at("seed"), 3);
  write_file_atomic(tmp / "bad.json", R"({"effects": {"rain": {"rate_mm_h": 1, "wnd_m_s": [1,0,0]}}})");
  const std::string bad = bin + " --quiet weather --in " + (tmp / "clean") + " --spec " + (tmp / "bad.json") +
                          " --out " + (tmp / "out2") + " 2>/dev/null";
  EXPECT_EQ(WEXITSTATUS(std::system(bad.c_str())), 2);
  EXPECT_EQ(std::system((bin + " weather --help > /dev/null").c_str()), 0);
}

}  // namespace
}  // namespace weathergs::generator
