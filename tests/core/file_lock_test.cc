// FileLock: one holder at a time across processes (fork) and across threads of one process; the
// waiter is told once; a lock that cannot be created names the path.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <thread>
#include <vector>

#include "core/error.h"
#include "core/file_lock.h"
#include "tests/core/test_util.h"

namespace weathergs {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

TEST(FileLock, ExcludesAnotherProcessUntilItReleases) {
  testing::TempDir tmp;
  const std::string lock = tmp / "entry.lock", held = tmp / "held";
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    {
      FileLock l(lock);
      std::FILE* f = std::fopen(held.c_str(), "w");
      if (f) std::fclose(f);
      std::this_thread::sleep_for(std::chrono::milliseconds(400));
    }
    _exit(0);
  }
  while (!fs::exists(held)) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  int told = 0;
  const auto t0 = Clock::now();
  {
    FileLock l(lock, [&] { ++told; });
    // The child held it for 400 ms after creating the marker; the wait must cover most of that.
    EXPECT_GE(std::chrono::duration<double>(Clock::now() - t0).count(), 0.2);
  }
  EXPECT_EQ(told, 1);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
  // Released: taken at once, nobody told to wait.
  FileLock again(lock, [&] { ++told; });
  EXPECT_EQ(told, 1);
  EXPECT_TRUE(fs::exists(lock));  // left in place on purpose (see file_lock.h)
}

TEST(FileLock, ExcludesThreadsOfOneProcess) {
  testing::TempDir tmp;
  const std::string lock = tmp / "entry.lock";
  std::atomic<int> inside{0}, overlaps{0}, waits{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&] {
      for (int i = 0; i < 5; ++i) {
        FileLock l(lock, [&] { ++waits; });
        if (++inside > 1) ++overlaps;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        --inside;
      }
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(overlaps.load(), 0);
  EXPECT_GT(waits.load(), 0);
}

TEST(FileLock, UncreatableLockFileIsAnInputErrorNamingIt) {
  testing::TempDir tmp;
  const std::string bad = tmp / "no_such_dir/entry.lock";
  try {
    FileLock l(bad);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), bad);
  }
  FileLock ok(tmp / "entry.lock");  // the failed attempt left no in-process claim behind
}

}  // namespace
}  // namespace weathergs
