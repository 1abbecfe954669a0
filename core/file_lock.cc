#include "core/file_lock.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <mutex>
#include <set>

#include "core/error.h"

namespace weathergs {
namespace {

// Paths locked by this process: record locks do not exclude threads of the same process.
std::mutex g_mutex;
std::condition_variable g_released;
std::set<std::string> g_held;

bool lock_record(int fd, bool wait) {
  struct flock fl {};
  fl.l_type = F_WRLCK;
  fl.l_whence = SEEK_SET;
  fl.l_start = 0;
  fl.l_len = 0;  // the whole file
  for (;;) {
    if (fcntl(fd, wait ? F_SETLKW : F_SETLK, &fl) == 0) return true;
    if (errno != EINTR) return false;  // errno says why (EACCES/EAGAIN: held elsewhere)
  }
}

}  // namespace

FileLock::FileLock(const std::string& path, const std::function<void()>& on_wait) : path_(path) {
  bool told = false;
  {
    std::unique_lock<std::mutex> lk(g_mutex);
    if (g_held.count(path_)) {
      if (on_wait) on_wait();
      told = true;
      g_released.wait(lk, [&] { return !g_held.count(path_); });
    }
    g_held.insert(path_);
  }
  auto release_slot = [&] {
    std::lock_guard<std::mutex> lk(g_mutex);
    g_held.erase(path_);
    g_released.notify_all();
  };
  fd_ = ::open(path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    const std::string why = std::strerror(errno);
    release_slot();
    throw InputError(path_, "cannot create the lock file: " + why);
  }
  if (!lock_record(fd_, false)) {
    const int first = errno;
    if (first != EACCES && first != EAGAIN) {
      ::close(fd_);
      release_slot();
      throw InputError(path_, std::string("cannot lock this file (does the file system support POSIX locks?): ") +
                                  std::strerror(first));
    }
    if (on_wait && !told) on_wait();
    if (!lock_record(fd_, true)) {
      const std::string why = std::strerror(errno);
      ::close(fd_);
      release_slot();
      throw InputError(path_, "waiting for the lock failed: " + why);
    }
  }
}

FileLock::~FileLock() {
  if (fd_ >= 0) ::close(fd_);  // closing releases the record lock
  std::lock_guard<std::mutex> lk(g_mutex);
  g_held.erase(path_);
  g_released.notify_all();
}

}  // namespace weathergs
