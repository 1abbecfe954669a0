#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/rng.h"
#include "core/sha256.h"
#include "tests/core/test_util.h"

namespace weathergs {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

TEST(RngTest, PhiloxKnownAnswers) {
  // Known-answer vectors of Random123 (kat_vectors, philox4x32_10).
  using A4 = std::array<uint32_t, 4>;
  EXPECT_EQ(philox4x32_10({0, 0, 0, 0}, {0, 0}), (A4{0x6627e8d5, 0xe169c58d, 0xbc57ac4c, 0x9b00dbd8}));
  EXPECT_EQ(philox4x32_10({0xffffffff, 0xffffffff, 0xffffffff, 0xffffffff}, {0xffffffff, 0xffffffff}),
            (A4{0x408f276d, 0x41c83b0e, 0xa20bc7c6, 0x6d5451fd}));
  EXPECT_EQ(philox4x32_10({0x243f6a88, 0x85a308d3, 0x13198a2e, 0x03707344}, {0xa4093822, 0x299f31d0}),
            (A4{0xd16cfe09, 0x94fdcceb, 0x5001e420, 0x24126ea1}));
}

TEST(RngTest, KeyedOnSeedStreamIndexOnly) {
  Rng a(7, 1, 42), b(7, 1, 42), c(7, 1, 43), d(8, 1, 42), e(7, 2, 42);
  for (int i = 0; i < 10; ++i) {
    uint32_t va = a.next_u32();
    EXPECT_EQ(va, b.next_u32());
    EXPECT_NE(va, c.next_u32());
    EXPECT_NE(va, d.next_u32());
    EXPECT_NE(va, e.next_u32());
  }
}

TEST(RngTest, UniformAndNormalMoments) {
  // Fixed seed: a deterministic check. Tolerances are ~5 standard errors for n = 200000.
  const int n = 200000;
  double su = 0, suu = 0, sn = 0, snn = 0;
  Rng r(1, 0, 0);
  for (int i = 0; i < n; ++i) {
    double u = r.uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    su += u;
    suu += u * u;
    double z = r.normal();
    ASSERT_TRUE(std::isfinite(z));
    sn += z;
    snn += z * z;
  }
  EXPECT_NEAR(su / n, 0.5, 5 * std::sqrt(1.0 / 12 / n));
  EXPECT_NEAR(suu / n - (su / n) * (su / n), 1.0 / 12, 0.002);
  EXPECT_NEAR(sn / n, 0.0, 5 / std::sqrt(double(n)));
  EXPECT_NEAR(snn / n, 1.0, 0.02);
  std::map<uint32_t, int> hist;
  for (int i = 0; i < 60000; ++i) hist[r.uniform_int(6)]++;
  EXPECT_EQ(hist.size(), 6u);
  for (auto& [k, v] : hist) EXPECT_NEAR(v, 10000, 500);
}

TEST(ProgressTest, EtaIsTheRateOfTheUnitsDoneHere) {
  // 69 iterations in 32 s after resuming at 9000 of 14500: 5431 left at 32/69 s each.
  EXPECT_DOUBLE_EQ(progress_eta_seconds(32.0, 69, 5431), 32.0 * 5431 / 69);
  EXPECT_EQ(progress_eta_seconds(32.0, 0, 10), 0.0);  // no rate yet
  EXPECT_EQ(progress_eta_seconds(32.0, 10, 0), 0.0);  // nothing left
}

TEST(ProgressTest, ResumedBarCountsFromWhereTheWorkStood) {
  const bool quiet = is_quiet();
  set_quiet(false);
  ::testing::internal::CaptureStderr();
  {
    ProgressBar bar("train", 100);  // stderr is captured, so the bar prints plain lines
    bar.resume_at(85);
    bar.tick(5);  // crosses 90%: one line
  }
  const std::string out = ::testing::internal::GetCapturedStderr();
  set_quiet(quiet);
  EXPECT_NE(out.find("train [###########################...] 90/100"), std::string::npos) << out;
  EXPECT_NE(out.find("90/100"), out.rfind("90/100")) << "the final summary repeats the count: " << out;
}

TEST(Sha256Test, Fips180Vectors) {
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(sha256_hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(ParallelTest, EveryIndexOnceAndChunksIndependentOfThreads) {
  for (int threads : {1, 2}) {
    set_num_threads(threads);
    std::vector<std::atomic<int>> hits(1000);
    parallel_for(0, 1000, [&](int64_t i) { hits[size_t(i)]++; });
    for (auto& h : hits) EXPECT_EQ(h.load(), 1);
    std::vector<std::pair<int64_t, int64_t>> chunks(size_t(num_chunks(5, 105, 30)));
    parallel_for_chunks(5, 105, 30, [&](int64_t k, int64_t lo, int64_t hi) { chunks[size_t(k)] = {lo, hi}; });
    EXPECT_EQ(chunks, (std::vector<std::pair<int64_t, int64_t>>{{5, 35}, {35, 65}, {65, 95}, {95, 105}}));
  }
  set_num_threads(0);
}

TEST(AtomicFileTest, FailedWriteLeavesNothing) {
  TempDir dir;
  EXPECT_THROW(write_file_atomic_with(dir / "out.json",
                                      [](const std::string& tmp) {
                                        write_file_atomic(tmp, "partial");
                                        throw InputError("x", "simulated failure");
                                      }),
               InputError);
  EXPECT_EQ(testing::count_entries(dir.path()), 0);
  write_file_atomic(dir / "out.json", "{}");
  EXPECT_EQ(read_file(dir / "out.json"), "{}");
}

TEST(AtomicFileTest, DirectoryAppearsOnlyOnCommit) {
  TempDir dir;
  {
    AtomicDirectory out(dir / "ds");
    write_file_atomic(out.path() + "/a.txt", "a");
    EXPECT_FALSE(fs::exists(dir / "ds"));
  }  // destroyed without commit
  EXPECT_EQ(testing::count_entries(dir.path()), 0);
  {
    AtomicDirectory out(dir / "ds");
    write_file_atomic(out.path() + "/a.txt", "a");
    out.commit();
  }
  EXPECT_EQ(read_file(dir / "ds/a.txt"), "a");
  {
    AtomicDirectory out(dir / "ds");  // replaces the old one
    write_file_atomic(out.path() + "/b.txt", "b");
    out.commit();
  }
  EXPECT_FALSE(fs::exists(dir / "ds/a.txt"));
  EXPECT_EQ(read_file(dir / "ds/b.txt"), "b");
  EXPECT_EQ(testing::count_entries(dir.path()), 1);
}

// Missing folders on the way to an output are created (mkdir -p, like `train --out`: the README's
// walk-through writes renders/ and results/ that a fresh clone lacks) and taken away again when the
// write fails or the directory is never committed; a file in the way is an InputError naming it.
TEST(AtomicFileTest, MissingFoldersAreCreatedAndRemovedOnFailure) {
  TempDir dir;
  write_file_atomic(dir / "a/b/out.json", "{}");
  EXPECT_EQ(read_file(dir / "a/b/out.json"), "{}");
  EXPECT_THROW(write_file_atomic_with(dir / "c/d/out.json", [](const std::string&) { throw InputError("x", "failed"); }),
               InputError);
  EXPECT_FALSE(fs::exists(dir / "c"));
  {
    AtomicDirectory out(dir / "e/f/ds");
    write_file_atomic(out.path() + "/a.txt", "a");
  }  // destroyed without commit: nothing of e/ is left
  EXPECT_FALSE(fs::exists(dir / "e"));
  {
    AtomicDirectory out(dir / "e/f/ds");
    write_file_atomic(out.path() + "/a.txt", "a");
    out.commit();
  }
  EXPECT_EQ(read_file(dir / "e/f/ds/a.txt"), "a");
  write_file_atomic(dir / "file", "x");
  try {
    write_file_atomic(dir / "file/g/out.json", "{}");
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), dir / "file/g/out.json");
    EXPECT_NE(std::string(e.what()).find("file"), std::string::npos) << e.what();
  }
  EXPECT_THROW(AtomicDirectory(dir / "file/h/ds"), InputError);
  EXPECT_EQ(testing::count_entries(dir.path()), 3);  // a, e, file
}

}  // namespace
}  // namespace weathergs
