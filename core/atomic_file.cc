#include "core/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "core/error.h"

namespace weathergs {

namespace fs = std::filesystem;

namespace {
// Unique per process and call; the name only has to avoid collisions, not be random.
std::string unique_suffix() {
  static std::atomic<uint64_t> counter{0};
  auto t = std::chrono::steady_clock::now().time_since_epoch().count();
  std::ostringstream s;
  s << ".tmp-" << ::getpid() << "-" << counter++ << "-" << (uint64_t(t) & 0xffff);
  return s.str();
}

// Removes the folders a failed write created (deepest first, each only if empty).
void remove_created(const std::vector<fs::path>& created) {
  std::error_code ec;
  for (auto it = created.rbegin(); it != created.rend(); ++it) fs::remove(*it, ec);
}

// Creates the missing folders on the way to `dir` (mkdir -p) and returns those it created, shallowest
// first, so that a failed write can take them away again (remove_created). `path` names the output
// in the error.
std::vector<fs::path> create_missing_folders(const fs::path& dir, const std::string& path) {
  std::vector<fs::path> missing;
  for (fs::path d = dir; !d.empty() && !fs::exists(d); d = d.parent_path()) {
    missing.push_back(d);
    if (d == d.root_path()) break;
  }
  std::vector<fs::path> created;
  for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
    std::error_code ec;
    if (fs::create_directory(*it, ec)) {
      created.push_back(*it);
    } else if (ec || !fs::is_directory(*it)) {  // not made by a concurrent run: in the way, or denied
      remove_created(created);
      throw InputError(path, "cannot create the output folder " + it->string() + ": " +
                                 (ec ? ec.message() : std::string("a file of that name is in the way")));
    }
  }
  return created;
}
}  // namespace

void write_file_atomic_with(const std::string& path, const std::function<void(const std::string&)>& write) {
  fs::path p(path);
  const std::vector<fs::path> created = create_missing_folders(p.parent_path(), path);
  fs::path tmp = p.parent_path() / (p.stem().string() + unique_suffix() + p.extension().string());
  try {
    write(tmp.string());
    fs::rename(tmp, p);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
    remove_created(created);
    throw;
  }
}

void write_file_atomic(const std::string& path, const std::string& contents) {
  write_file_atomic_with(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw InputError(path, "cannot open for writing");
    out.write(contents.data(), std::streamsize(contents.size()));
    out.flush();
    if (!out) throw InputError(path, "write failed (disk full?)");
  });
}

void check_writable_destination(const std::string& path, const std::string& what) {
  std::error_code ec;
  fs::path p = fs::absolute(fs::path(path), ec).lexically_normal();
  if (ec) throw InputError(path, what + ": cannot resolve the path: " + ec.message());
  while (!p.empty() && !fs::exists(p, ec)) {
    if (p == p.parent_path()) break;
    p = p.parent_path();
  }
  if (!fs::is_directory(p, ec))
    throw InputError(path, what + ": " + p.string() + " exists and is not a folder, so the output cannot be made there");
  // access() answers for the real user, as the later writes will be made (root passes it anyway).
  if (::access(p.c_str(), W_OK | X_OK) != 0)
    throw InputError(path, what + ": the folder " + p.string() + " is not writable; choose another output or fix its permissions");
}

void copy_tree(const std::string& from, const std::string& to) {
  fs::create_directories(to);
  fs::copy(from, to, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file (missing or unreadable)");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

AtomicDirectory::AtomicDirectory(const std::string& final_path) : final_path_(final_path) {
  fs::path p = fs::absolute(final_path).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  final_path_ = p.string();
  created_parents_ = create_missing_folders(p.parent_path(), final_path);
  tmp_path_ = final_path_ + unique_suffix();
  std::error_code ec;
  fs::create_directories(tmp_path_, ec);
  if (ec) {
    remove_created(created_parents_);
    throw InputError(final_path, "cannot create the output folder here: " + ec.message());
  }
}

AtomicDirectory::~AtomicDirectory() {
  if (!committed_) {
    std::error_code ec;
    fs::remove_all(tmp_path_, ec);
    remove_created(created_parents_);
  }
}

void AtomicDirectory::commit() {
  WGS_CHECK(!committed_);
  std::error_code ec;
  if (fs::exists(final_path_)) {
    // Move the old one aside first so that the swap is two renames; remove it afterwards.
    std::string old = final_path_ + unique_suffix() + ".old";
    fs::rename(final_path_, old);
    fs::rename(tmp_path_, final_path_);
    fs::remove_all(old, ec);
  } else {
    fs::rename(tmp_path_, final_path_);
  }
  committed_ = true;
}

}  // namespace weathergs
