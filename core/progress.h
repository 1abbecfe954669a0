// A progress bar for long loops, on stderr. On a terminal it redraws one line; otherwise (a log
// file, a workflow) it prints a plain line at every tenth of the work, at least every 30 s, and a
// final summary. set_quiet(true) (the CLI's --quiet) silences both.
// Thread-safe: tick() may be called from any worker.
#pragma once

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>

namespace weathergs {

// Peak resident set size of this process in MiB (getrusage).
double peak_rss_mb();

// Wall-clock seconds elapsed since t (steady clock).
double seconds_since(std::chrono::steady_clock::time_point t);

// CPU seconds this process has used so far, every thread's (CLOCK_PROCESS_CPUTIME_ID): unlike wall
// time, a one-thread job's CPU seconds do not grow when other jobs share the cores.
double process_cpu_seconds();

void set_quiet(bool quiet);
bool is_quiet();

// Seconds left at the rate seen so far: `seconds` spent on `done_here` units, `left` units to go.
// 0 before any unit is done.
double progress_eta_seconds(double seconds, int64_t done_here, int64_t left);

class ProgressBar {
 public:
  ProgressBar(std::string label, int64_t total);
  ~ProgressBar();
  // Work resumed part way (a training from its checkpoint): the first `done` units count toward the
  // bar but not toward the rate, and the clock restarts, so that the ETA is this run's own rate.
  // Call it before the first tick.
  void resume_at(int64_t done);
  void tick(int64_t n = 1);
  // Free text shown after the counter (e.g. "loss 0.031 psnr 27.4"); thread-safe.
  void set_status(const std::string& status);
  void finish();

 private:
  void draw(bool final);
  std::string label_;
  int64_t total_;
  std::atomic<int64_t> done_{0};
  int64_t resumed_ = 0;  // units done before this process started on them
  std::string status_;
  std::mutex mutex_;
  bool interactive_, finished_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace weathergs
