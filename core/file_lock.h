// An exclusive lock on a file shared by processes, on one machine or several (a cluster's shared file
// system): POSIX record locks (fcntl), which Linux NFS clients forward to the server's lock manager,
// unlike flock() on older kernels. Threads of one process also exclude each other (record locks alone
// are per process). The lock file is left in place: deleting it would let a waiting process lock an
// unlinked file while a newcomer locks a new one.
#pragma once

#include <functional>
#include <string>

namespace weathergs {

class FileLock {
 public:
  // Blocks until the lock on `path` (created if missing) is held. `on_wait` is called once, before
  // blocking, when another holder has it (to tell the user what the pause is). InputError when the
  // file cannot be created or locked (e.g. a file system without lock support), naming the path.
  explicit FileLock(const std::string& path, const std::function<void()>& on_wait = {});
  ~FileLock();
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int fd_ = -1;
};

}  // namespace weathergs
