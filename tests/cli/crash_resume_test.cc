// kill -9 at random points of `train`, `weather` and `generate` (docs/reliability.md): afterwards
// the output path holds the previous complete output or nothing (temporaries named *.tmp-* may
// remain; nothing ever reads them), and `train --resume` after a kill ends in the same model, byte
// for byte, as an uninterrupted run. Slow: a few minutes.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <thread>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/rng.h"
#include "capture/process.h"
#include "tests/core/test_util.h"
#include "tests/generator/test_scene.h"

namespace weathergs {
namespace {

namespace fs = std::filesystem;
constexpr int kTrials = 20;  // per command (the required minimum)

// Starts `weathergs args` and kills it with SIGKILL after `delay_s`; returns true if it was still
// running (killed), false if it had finished.
bool run_and_kill(const std::vector<std::string>& args, double delay_s, const std::string& log) {
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    dup2(fd, 1);
    dup2(fd, 2);
    std::vector<char*> argv;
    std::vector<std::string> all = {WEATHERGS_BINARY, "--quiet"};
    all.insert(all.end(), args.begin(), args.end());
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(WEATHERGS_BINARY, argv.data());
    _exit(127);
  }
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(delay_s);
  int status = 0;
  while (std::chrono::steady_clock::now() < end) {
    if (waitpid(pid, &status, WNOHANG) == pid) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  kill(pid, SIGKILL);
  waitpid(pid, &status, 0);
  return true;
}

int run(const std::string& args, const std::string& log) {
  const int st = std::system((std::string(WEATHERGS_BINARY) + " --quiet " + args + " > '" + log + "' 2>&1").c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

bool is_temporary(const fs::path& p) { return p.filename().string().find(".tmp-") != std::string::npos; }

// A dataset folder is either absent or complete: readable, every view's images present.
void expect_absent_or_complete_dataset(const std::string& dir, const std::string& what) {
  if (!fs::exists(dir)) return;
  const Dataset d = read_dataset(dir);  // throws (fails the test) if half-written
  for (const Camera& c : d.cameras) {
    EXPECT_TRUE(fs::exists(d.path(ImageKind::kImages, c.name))) << what << " " << c.name;
    EXPECT_NO_THROW(read_image(d.path(ImageKind::kImages, c.name))) << what << " " << c.name;
  }
  for (const auto& e : fs::recursive_directory_iterator(dir)) EXPECT_FALSE(is_temporary(e.path())) << e.path();
}

struct Fixture {
  testing::TempDir tmp;
  std::string data;
  Fixture() {
    testing::SceneOptions so;
    so.views = 9;
    data = tmp / "data";
    testing::make_clean_dataset(data, so);
    copy_tree(data + "/clean", data + "/images");
  }
};

TEST(CrashResume, TrainKilledAnywhereResumesToTheSameModel) {
  Fixture f;
  const std::string common = " --iterations 120 --random-init-count 300 --seed 4 --checkpoint-every 10";
  ASSERT_EQ(run("train --data " + f.data + common + " --out " + (f.tmp / "ref"), f.tmp / "ref.log"), 0);
  const std::string ref_ply = read_file(f.tmp / "ref/point_cloud.ply");
  Rng rng(7, 1, 0);
  int killed = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const std::string out = f.tmp / ("run" + std::to_string(trial));
    const double delay = 0.05 + 2.0 * rng.uniform_double();
    killed += run_and_kill({"train", "--data", f.data, "--iterations", "120", "--random-init-count", "300", "--seed", "4",
                            "--checkpoint-every", "10", "--out", out},
                           delay, f.tmp / "kill.log");
    // What is on disk is complete: run.json parses, and the checkpoint (if any) loads on resume.
    if (fs::exists(out + "/run.json")) { EXPECT_NO_THROW(read_json_file(out + "/run.json")); }
    if (fs::exists(out + "/checkpoint.bin")) {
      ASSERT_EQ(run("train --resume --out " + out, f.tmp / "resume.log"), 0) << read_file(f.tmp / "resume.log");
    } else {
      // Killed before the first checkpoint: start again (the out folder may hold nothing else).
      ASSERT_EQ(run("train --data " + f.data + common + " --force --out " + out, f.tmp / "resume.log"), 0)
          << read_file(f.tmp / "resume.log");
    }
    EXPECT_EQ(read_file(out + "/point_cloud.ply"), ref_ply) << "resumed model differs from the uninterrupted one";
    fs::remove_all(out);
  }
  std::printf("train: %d of %d trials killed mid-run\n", killed, kTrials);
  EXPECT_GE(killed, kTrials / 2);
}

TEST(CrashResume, WeatherKilledAnywhereLeavesNothingOrTheOldOutput) {
  Fixture f;
  write_file_atomic(f.tmp / "spec.json", R"({"seed": 2, "style": "paper", "effects": {"rain": {"intensity": "heavy"},
      "lens_droplets": {"count": 10}}})");
  const std::string args_out = f.tmp / "w";
  Rng rng(7, 2, 0);
  int killed = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    // Half the trials start from a previous complete output that must survive a killed rewrite.
    const bool previous = trial % 2 == 1;
    if (previous) { ASSERT_EQ(run("weather --in " + f.data + " --spec " + (f.tmp / "spec.json") + " --out " + args_out, f.tmp / "w.log"), 0); }
    const std::string before = previous ? read_file(args_out + "/images/004.png") : "";
    killed += run_and_kill({"weather", "--in", f.data, "--spec", f.tmp / "spec.json", "--out", args_out, "--seed",
                            std::to_string(trial + 10)},
                           0.02 + 0.6 * rng.uniform_double(), f.tmp / "kill.log");
    expect_absent_or_complete_dataset(args_out, "weather");
    if (previous && fs::exists(args_out)) {
      const std::string after = read_file(args_out + "/images/004.png");
      const Dataset d = read_dataset(args_out);
      // Either the old output (seed 2) or the new one, complete.
      EXPECT_TRUE(after == before || d.info.generator->at("seed").get<int>() == trial + 10);
    }
    fs::remove_all(args_out);
    for (const auto& e : fs::directory_iterator(f.tmp.path()))
      if (is_temporary(e.path())) fs::remove_all(e.path());
  }
  std::printf("weather: %d of %d trials killed mid-run\n", killed, kTrials);
  EXPECT_GE(killed, kTrials / 2);
}

TEST(CrashResume, GenerateKilledAnywhereLeavesNothing) {
  if (capture::find_executable("blender").empty()) GTEST_SKIP() << "blender not installed";
  testing::TempDir tmp;
  const std::string scene = std::string(WEATHERGS_SOURCE_DIR) + "/scenes/pool.json";
  const std::string base = "generate --scene " + scene + " --weather rain --profile tiny --no-colmap --max-views 2 --cache " +
                           (tmp / "cache");
  // Warm the cache once (timed: a cold render), then time a cached run: the kill moments are drawn
  // within each run's own duration, so most trials really kill it mid-run.
  auto timed = [&](const std::string& args, const std::string& log) {
    const auto t0 = std::chrono::steady_clock::now();
    const int rc = run(args, log);
    EXPECT_EQ(rc, 0) << read_file(log);
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  const double cold_s = timed(base + " --out " + (tmp / "warm"), tmp / "warm.log");
  const double cached_s = timed(base + " --out " + (tmp / "warm2"), tmp / "warm2.log");
  std::printf("generate: cold %.1f s, cached %.1f s\n", cold_s, cached_s);
  Rng rng(7, 3, 0);
  int killed = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    SCOPED_TRACE("trial " + std::to_string(trial));
    const std::string out = tmp / "g";
    // Every fourth trial renders into a fresh cache (the kill may hit Blender or the cache commit).
    const bool cold = trial % 4 == 3;
    const std::string cache = cold ? tmp / ("cache_cold_" + std::to_string(trial)) : tmp / "cache";
    const double duration = cold ? cold_s : cached_s;
    killed += run_and_kill({"generate", "--scene", scene, "--weather", "rain", "--profile", "tiny", "--no-colmap",
                            "--max-views", "2", "--cache", cache, "--out", out, "--seed", std::to_string(trial)},
                           duration * (0.02 + 0.9 * rng.uniform_double()), tmp / "kill.log");
    expect_absent_or_complete_dataset(out, "generate");
    fs::remove_all(out);
    // The cache entry is never half-written either: afterwards the cache works (a hit when the
    // killed run had committed its entry, else a clean render).
    ASSERT_EQ(run(base.substr(0, base.find(" --cache ")) + " --cache " + cache + " --out " + out, tmp / "after.log"), 0)
        << read_file(tmp / "after.log");
    if (!cold) { EXPECT_NE(read_file(tmp / "after.log").find("(cached)"), std::string::npos); }
    expect_absent_or_complete_dataset(out, "generate after the kill");
    fs::remove_all(out);
  }
  std::printf("generate: %d of %d trials killed mid-run\n", killed, kTrials);
  EXPECT_GE(killed, kTrials / 2);
}

}  // namespace
}  // namespace weathergs
