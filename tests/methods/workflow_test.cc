// workflow/Snakefile end to end on the tiny profile: one variant, two methods, one seed; then a
// re-run does nothing, a removed result is the only cell run again, and runs added to the results
// archive are restored, not trained, once their folders are gone, and `make results` tabulates them.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "core/atomic_file.h"
#include "capture/process.h"
#include "evaluator/results.h"
#include "tests/core/test_util.h"

namespace weathergs::methods {
namespace {

namespace fs = std::filesystem;

TEST(Workflow, TinySuiteRunsResumesAndRerunsOnlyWhatIsMissing) {
  for (const char* tool : {"snakemake", "blender", "colmap"})
    if (capture::find_executable(tool).empty()) GTEST_SKIP() << tool << " not installed";
  testing::TempDir tmp;
  const std::string src = WEATHERGS_SOURCE_DIR;
  const std::string out = tmp / "suite";
  const std::string cmd = "cd '" + std::string(tmp.path()) + "' && USER=${USER:-weathergs} snakemake -s " + src +
                          "/workflow/Snakefile --cores 2 --config weathergs=" + WEATHERGS_BINARY + " scenes=" + src +
                          "/scenes out=" + out + " cache=" + (tmp / "cache") +
                          " 'variants=[pool_rain]' 'methods=[3dgs,oracle]' 'seeds=[1]' iterations=150";
  auto run = [&](const std::string& log, const std::string& more_config = "") {
    const int st = std::system((cmd + more_config + " > '" + log + "' 2>&1").c_str());
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  };
  ASSERT_EQ(run(tmp / "1.log"), 0) << read_file(tmp / "1.log");
  const std::string md = read_file(out + "/leaderboard.md");
  for (const char* m : {"3dgs", "oracle"}) EXPECT_NE(md.find(m), std::string::npos) << md;
  EXPECT_TRUE(fs::exists(out + "/leaderboard.html"));
  EXPECT_TRUE(fs::exists(out + "/report/index.html") && fs::exists(out + "/report/data.js"));  // the results browser
  const std::string tables = read_file(out + "/tables.md");  // leaderboard --paper
  EXPECT_NE(tables.find("## Table I: Rain"), std::string::npos) << tables;
  EXPECT_NE(tables.find("| oracle (reference) |"), std::string::npos) << tables;
  EXPECT_NE(tables.find("computational cost"), std::string::npos) << tables;
  // Accuracy against time: every run scored at 1/8, 1/4, 1/2 of its 150 iterations and at the end.
  const std::string curves = read_file(out + "/curves.csv");
  EXPECT_EQ(curves.rfind("variant,method,seed,iteration,train_seconds,psnr,ssim,lpips,num_gaussians\n", 0), 0u) << curves;
  for (const char* row : {"pool_rain,3dgs,1,18,", "pool_rain,3dgs,1,150,", "pool_rain,oracle,1,75,"})
    EXPECT_NE(curves.find(row), std::string::npos) << row << "\n" << curves;
  EXPECT_EQ(read_file(out + "/curves/pool_rain.png").substr(1, 3), "PNG");
  // NerfBaselines' layout next to ours.
  const Json nb = read_json_file(out + "/nerfbaselines/pool_rain/3dgs/seed1/results.json");
  EXPECT_EQ(nb.at("evaluation_protocol"), "default");
  EXPECT_EQ(nb.at("predictions_sha256").get<std::string>().size(), 64u);
  // Each cell's output reaches the terminal tagged with the cell, trainer progress included.
  const std::string log1 = read_file(tmp / "1.log");
  EXPECT_NE(log1.find("[pool_rain 3dgs seed1] "), std::string::npos) << log1;
  EXPECT_NE(read_file(out + "/logs/reconstruct/pool_rain_3dgs_seed1.log").find("/150"), std::string::npos);
  const evaluator::Results r3 = evaluator::read_results(out + "/runs/pool_rain/3dgs/seed1/results.json");
  const evaluator::Results ro = evaluator::read_results(out + "/runs/pool_rain/oracle/seed1/results.json");
  std::printf("tiny pool_rain, 150 iterations: 3dgs %.2f dB, oracle %.2f dB\n", r3.metrics.psnr, ro.metrics.psnr);
  // Everything up to date: nothing runs.
  ASSERT_EQ(run(tmp / "2.log"), 0) << read_file(tmp / "2.log");
  EXPECT_NE(read_file(tmp / "2.log").find("Nothing to be done"), std::string::npos) << read_file(tmp / "2.log");
  // One result gone (with the leaderboard that needs it: Snakemake does not rebuild an intermediate
  // file that nothing out of date needs): only that cell and the leaderboard run again, the trained
  // model is reused.
  const std::string ply = read_file(out + "/runs/pool_rain/oracle/seed1/model/point_cloud.ply");
  fs::remove(out + "/runs/pool_rain/oracle/seed1/results.json");
  fs::remove(out + "/leaderboard.md");
  ASSERT_EQ(run(tmp / "3.log"), 0) << read_file(tmp / "3.log");
  const std::string log3 = read_file(tmp / "3.log");
  EXPECT_EQ(log3.find("rule generate"), std::string::npos) << log3;
  size_t jobs = 0;
  for (size_t at = log3.find("rule reconstruct:"); at != std::string::npos; at = log3.find("rule reconstruct:", at + 1)) ++jobs;
  EXPECT_EQ(jobs, 1u) << log3;
  EXPECT_EQ(read_file(out + "/runs/pool_rain/oracle/seed1/model/point_cloud.ply"), ply);
  EXPECT_TRUE(fs::exists(out + "/runs/pool_rain/oracle/seed1/results.json"));
  // The results archive (docs/archive.md): both runs added, every run folder deleted, the suite run
  // again with the archive: each cell is restored (its recipe unchanged), nothing trains, and the
  // leaderboard is the same, byte for byte.
  const std::string archive = tmp / "results";
  for (const char* m : {"3dgs", "oracle"}) {
    const auto added = weathergs::testing::run_command(std::string(WEATHERGS_BINARY) + " archive add " + out +
                                                       "/runs/pool_rain/" + m + "/seed1 --root " + archive + " --suite tiny");
    ASSERT_EQ(added.exit_code, 0) << added.output;
  }
  const std::string board = read_file(out + "/leaderboard.md");
  fs::remove_all(out + "/runs");
  ASSERT_EQ(run(tmp / "4.log", " archive=" + archive + "/tiny"), 0) << read_file(tmp / "4.log");
  const std::string log4 = read_file(tmp / "4.log");
  EXPECT_EQ(log4.find("rule generate"), std::string::npos) << log4;
  for (const char* m : {"3dgs", "oracle"}) {
    const std::string cell = std::string("[pool_rain ") + m + " seed1] restored from archive: " + archive + "/tiny/pool_rain/" + m;
    EXPECT_NE(log4.find(cell), std::string::npos) << cell << "\n" << log4;
    EXPECT_FALSE(fs::exists(out + "/runs/pool_rain/" + m + "/seed1/model")) << m << " trained";
    EXPECT_EQ(read_file(out + "/runs/pool_rain/" + m + "/seed1/results.json"),
              read_file(archive + "/tiny/pool_rain/" + m + "/seed1/results.json"));
  }
  EXPECT_EQ(log4.find("reconstruct: training"), std::string::npos) << log4;
  EXPECT_EQ(read_file(out + "/leaderboard.md"), board);
  EXPECT_TRUE(fs::exists(out + "/report/index.html"));  // the results browser, with the restored runs' numbers
  // `make results` reads docs/results.md's tables from such an archive (the script's own checks).
  const auto made = weathergs::testing::run_command("bash " + src + "/tests/methods/results_tables_test.sh " +
                                                    WEATHERGS_BINARY + " " + (tmp / "tables") + " " + src + " " +
                                                    archive + "/tiny");
  EXPECT_EQ(made.exit_code, 0) << made.output;
}

// `iterations: fast` (a dry run): no --iterations, the curve as fractions of each run's own length,
// and the cluster's time request from the fast length of the variant's profile (tiny: 4 training
// views, 3000 iterations; quick: 14, 7000), so quick asks more time than tiny.
TEST(Workflow, FastIterationsLetEachRunTakeItsOwnLength) {
  if (capture::find_executable("snakemake").empty()) GTEST_SKIP() << "snakemake not installed";
  testing::TempDir tmp;
  const std::string src = WEATHERGS_SOURCE_DIR;
  auto dry_run = [&](const std::string& profile) {
    const std::string log = tmp / (profile + ".log");
    const std::string cmd = "cd '" + std::string(tmp.path()) + "' && USER=${USER:-weathergs} snakemake -n -p -s " + src +
                            "/workflow/Snakefile --cores 2 --config weathergs=" + WEATHERGS_BINARY + " scenes=" + src +
                            "/scenes out=" + (tmp / profile) + " profile=" + profile +
                            " 'variants=[pool_rain]' 'methods=[3dgs]' 'seeds=[0]' iterations=fast > '" + log + "' 2>&1";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << read_file(log);
    return read_file(log);
  };
  auto runtime = [](const std::string& log) {
    const size_t at = log.find("rule reconstruct:");
    const size_t r = log.find("runtime=", at);
    return at == std::string::npos || r == std::string::npos ? -1 : std::atoi(log.c_str() + r + 8);
  };
  const std::string tiny = dry_run("tiny"), quick = dry_run("quick");
  const size_t cmd = tiny.find(" reconstruct --data ");
  ASSERT_NE(cmd, std::string::npos) << tiny;
  const std::string line = tiny.substr(cmd, tiny.find('\n', cmd) - cmd);
  EXPECT_EQ(line.find("--iterations"), std::string::npos) << line;
  EXPECT_NE(line.find("--eval-at-fractions 0.125,0.25,0.5"), std::string::npos) << line;
  // config.yaml: tiny 5 + 5 per 1000 iterations, quick 10 + 5 per 1000.
  EXPECT_EQ(runtime(tiny), 20) << tiny;
  EXPECT_EQ(runtime(quick), 45) << quick;
}

// Two-thread generations go before one-thread trainings under the greedy scheduler (the one
// `--prioritize` needs, docs/archive.md): otherwise a training started after the first generation
// holds one core, and the second generation waits for it with the other core idle. A stand-in
// binary logs each command's start and end, so the test needs neither Blender nor training.
TEST(Workflow, GenerationsGoBeforeTrainingsUnderTheGreedyScheduler) {
  if (capture::find_executable("snakemake").empty()) GTEST_SKIP() << "snakemake not installed";
  testing::TempDir tmp;
  const std::string src = WEATHERGS_SOURCE_DIR;
  const std::string events = tmp / "events.txt", fake = tmp / "weathergs";
  write_file_atomic(fake, "#!/usr/bin/env bash\n"
                          "cmd=; out=; prev=\n"
                          "for a in \"$@\"; do\n"
                          "  case $a in doctor|generate|reconstruct) [ -z \"$cmd\" ] && cmd=$a ;; esac\n"
                          "  [ \"$prev\" = --out ] && out=$a; prev=$a\n"
                          "done\n"
                          "[ \"$cmd\" = doctor ] && exit 0\n"
                          "echo \"start $cmd\" >> '" + events + "'\n"
                          "sleep 2; mkdir -p \"$out\"\n"
                          "if [ \"$cmd\" = generate ]; then echo '{}' > \"$out/dataset.json\"; "
                          "else echo '{}' > \"$out/results.json\"; echo '{}' > \"$out/curve.json\"; fi\n"
                          "echo \"end $cmd\" >> '" + events + "'\n");
  fs::permissions(fake, fs::perms::owner_all);
  const std::string out = tmp / "suite", log = tmp / "snakemake.log";
  const std::string cmd = "cd '" + std::string(tmp.path()) + "' && USER=${USER:-weathergs} snakemake -s " + src +
                          "/workflow/Snakefile --cores 2 --scheduler greedy " + out +
                          "/runs/pool_rain/3dgs/seed0/results.json " + out +
                          "/runs/pool_snow/3dgs/seed0/results.json --config weathergs=" + fake + " scenes=" + src +
                          "/scenes out=" + out + " threads=1 'variants=[pool_rain,pool_snow]' 'methods=[3dgs]' " +
                          "'seeds=[0]' > '" + log + "' 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << read_file(log);
  // Only the generations' place is asserted: how the two trainings interleave depends on the load.
  const std::string order = read_file(events);
  const std::string generations = "start generate\nend generate\nstart generate\nend generate\n";
  EXPECT_EQ(order.substr(0, generations.size()), generations) << "the commands ran in this order:\n" << order;
  EXPECT_EQ(order.size(), generations.size() + 2 * std::string("start reconstruct\nend reconstruct\n").size()) << order;
}

}  // namespace
}  // namespace weathergs::methods
