// Shared by the libFuzzer harnesses (fuzz/README.md): the input is written to a scratch file the
// reader under test opens. InputError is the expected answer to bad input; any other exception is a
// bug, so it aborts (libFuzzer then saves the input as a crash).
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.h"

namespace weathergs::fuzz {

inline const std::string* scratch_dir_ptr();

// A per-process scratch folder, removed at exit.
inline const std::string& scratch_dir() {
  // Never freed, so that the atexit cleanup below cannot run after its destruction (a static
  // std::string is destroyed before an atexit handler registered during its initialization runs).
  static const std::string* dir = [] {
    auto* d = new std::string(std::filesystem::temp_directory_path().string() + "/weathergs_fuzz_" +
                              std::to_string(::getpid()));
    std::filesystem::create_directories(*d);
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(*scratch_dir_ptr(), ec);
    });
    return d;
  }();
  return *dir;
}

inline const std::string* scratch_dir_ptr() { return &scratch_dir(); }

inline std::string write_input(const uint8_t* data, size_t size, const std::string& name) {
  const std::string path = scratch_dir() + "/" + name;
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data), std::streamsize(size));
  return path;
}

// Runs f; InputError is fine, anything else aborts with its message.
template <typename F>
int expect_only_input_errors(F&& f) {
  try {
    f();
  } catch (const InputError&) {
  } catch (const std::exception& e) {
    std::fprintf(stderr, "unexpected exception (not an InputError): %s\n", e.what());
    std::abort();
  }
  return 0;
}

}  // namespace weathergs::fuzz
