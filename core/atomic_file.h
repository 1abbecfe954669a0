// Atomic outputs: write to a temporary sibling, then rename over the destination. A failed or killed
// run leaves either the old file or the complete new one, never half a file. Missing folders on the
// way to an output are created (like `mkdir -p`, and like `train --out`) and removed again when the
// write fails, so a failed run leaves no empty folders behind either.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace weathergs {

// Calls write(tmp_path) and renames tmp_path to path on success; on any exception the temp file is
// removed and the exception propagates. The temp name keeps the extension: "a.png" -> "a.tmp-<r>.png".
void write_file_atomic_with(const std::string& path, const std::function<void(const std::string&)>& write);
void write_file_atomic(const std::string& path, const std::string& contents);

// Copies the folder `from` into `to` recursively (created if needed; existing files are overwritten).
void copy_tree(const std::string& from, const std::string& to);

// Checks, before any work, that `path` can be made or written: the path itself, when it exists, must be
// a writable folder, else its nearest existing ancestor must be one. InputError naming `what` and the
// folder that refuses it.
void check_writable_destination(const std::string& path, const std::string& what);

// Reads a whole file; InputError if missing or unreadable.
std::string read_file(const std::string& path);

// A directory that becomes visible at `final_path` only when commit() is called: work happens in
// "<final_path>.tmp-<random>", which is removed if the object is destroyed without commit().
// commit() replaces an existing final_path (the old one is removed only after the new one is complete).
class AtomicDirectory {
 public:
  explicit AtomicDirectory(const std::string& final_path);
  ~AtomicDirectory();
  AtomicDirectory(const AtomicDirectory&) = delete;
  AtomicDirectory& operator=(const AtomicDirectory&) = delete;

  const std::string& path() const { return tmp_path_; }  // where to write now
  const std::string& final_path() const { return final_path_; }
  void commit();

 private:
  std::string final_path_, tmp_path_;
  std::vector<std::filesystem::path> created_parents_;  // removed again unless committed
  bool committed_ = false;
};

}  // namespace weathergs
