#include "core/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>

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
}  // namespace

void write_file_atomic_with(const std::string& path, const std::function<void(const std::string&)>& write) {
  fs::path p(path);
  if (p.has_parent_path() && !fs::exists(p.parent_path()))
    throw InputError(path, "output directory " + p.parent_path().string() + " does not exist");
  fs::path tmp = p.parent_path() / (p.stem().string() + unique_suffix() + p.extension().string());
  try {
    write(tmp.string());
    fs::rename(tmp, p);
  } catch (...) {
    std::error_code ec;
    fs::remove(tmp, ec);
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
  if (!fs::exists(p.parent_path()))
    throw InputError(final_path, "parent directory " + p.parent_path().string() + " does not exist");
  tmp_path_ = final_path_ + unique_suffix();
  std::error_code ec;
  fs::create_directories(tmp_path_, ec);
  if (ec) throw InputError(final_path, "cannot create the output folder here: " + ec.message());
}

AtomicDirectory::~AtomicDirectory() {
  if (!committed_) {
    std::error_code ec;
    fs::remove_all(tmp_path_, ec);
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
