#include "core/progress.h"

#include <sys/resource.h>

#include <unistd.h>

#include <cstdio>
#include <ctime>

namespace weathergs {

double peak_rss_mb() {
  struct rusage ru {};
  getrusage(RUSAGE_SELF, &ru);
  return double(ru.ru_maxrss) / 1024.0;  // Linux reports KiB
}

double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}

double process_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

namespace {
std::atomic<bool> g_quiet{false};
}
void set_quiet(bool quiet) { g_quiet = quiet; }
bool is_quiet() { return g_quiet; }

ProgressBar::ProgressBar(std::string label, int64_t total)
    : label_(std::move(label)), total_(total), interactive_(!g_quiet && ::isatty(STDERR_FILENO)),
      start_(std::chrono::steady_clock::now()), last_draw_(start_) {}

ProgressBar::~ProgressBar() { finish(); }

double progress_eta_seconds(double seconds, int64_t done_here, int64_t left) {
  return done_here > 0 && left > 0 ? seconds * double(left) / double(done_here) : 0.0;
}

void ProgressBar::resume_at(int64_t done) {
  std::lock_guard<std::mutex> lock(mutex_);
  done_ = done;
  resumed_ = done;
  start_ = last_draw_ = std::chrono::steady_clock::now();
}

void ProgressBar::tick(int64_t n) {
  const int64_t before = done_.fetch_add(n);
  if (g_quiet) return;
  auto now = std::chrono::steady_clock::now();
  std::lock_guard<std::mutex> lock(mutex_);
  if (interactive_) {
    if (now - last_draw_ > std::chrono::milliseconds(100) || done_ >= total_) {
      last_draw_ = now;
      draw(false);
    }
    return;
  }
  // Logs (stderr not a terminal): one plain line at every tenth of the work and at least every
  // 30 s, so a log read while the job runs shows where it is.
  const int64_t after = before + n;
  const bool next_tenth = total_ > 0 && (after * 10 / total_) > (before * 10 / total_) && after < total_;
  if (next_tenth || now - last_draw_ > std::chrono::seconds(30)) {
    last_draw_ = now;
    draw(false);
  }
}

void ProgressBar::set_status(const std::string& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  status_ = status;
}

void ProgressBar::draw(bool final) {
  double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  int64_t done = done_;
  double frac = total_ > 0 ? double(done) / double(total_) : 1.0;
  const int width = 30;
  int filled = int(frac * width + 0.5);
  std::string bar(size_t(filled < 0 ? 0 : filled > width ? width : filled), '#');
  bar.resize(width, '.');
  const double eta = progress_eta_seconds(secs, done - resumed_, total_ - done);
  std::fprintf(stderr, "%s%s [%s] %lld/%lld %.1fs%s%s %s%s", interactive_ ? "\r" : "", label_.c_str(), bar.c_str(),
               (long long)done, (long long)total_, secs,
               final ? "" : " eta ", final ? "" : std::to_string(int(eta)).append("s").c_str(),
               status_.c_str(), interactive_ ? "\033[K" : "");
  if (final || !interactive_) std::fputc('\n', stderr);
  std::fflush(stderr);
}

void ProgressBar::finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  if (!g_quiet) draw(true);
}

}  // namespace weathergs
