// The trainers' numerics goldens (tests/data/numerics_golden.json): per backend, the numerics
// version they were made under (reconstruction/numerics.h, nerf/numerics.h) and the sha256 of the
// parameters each small fixed training case ends with. A run's recipe records the version
// (docs/archive.md), so bits that move while it stays would let results of two trainers pass for
// one recipe: the check fails then, and when the version moved but the golden was not made anew.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <map>
#include <string>

#include "core/atomic_file.h"
#include "core/json_reader.h"
#include "core/sha256.h"

namespace weathergs::testing {

inline const std::string kNumericsGoldenFile = std::string(WEATHERGS_SOURCE_DIR) + "/tests/data/numerics_golden.json";
inline const char* kRegenerateNumericsGolden =
    "WEATHERGS_WRITE_NUMERICS_GOLDEN=1 ctest --test-dir BUILD -R numerics_golden (then commit "
    "tests/data/numerics_golden.json)";

// The sha256 of the arrays' bytes, in order.
template <typename... Arrays>
std::string sha256_of_arrays(const Arrays&... arrays) {
  Sha256 h;
  (h.update(arrays.data(), arrays.size() * sizeof(arrays[0])), ...);
  return h.hex_digest();
}

// Compares `hashes` (case -> sha256) with the golden of `backend`, made under `version`; with
// WEATHERGS_WRITE_NUMERICS_GOLDEN=1 writes them as the golden instead. `constant` names the version
// constant and its header, for the message.
inline void check_numerics_golden(const std::string& backend, const std::string& version, const std::string& constant,
                                  const std::map<std::string, std::string>& hashes) {
  const char* write = std::getenv("WEATHERGS_WRITE_NUMERICS_GOLDEN");
  if (write && std::string(write) == "1") {
    Json golden = std::filesystem::exists(kNumericsGoldenFile) ? read_json_file(kNumericsGoldenFile) : Json::object();
    golden[backend] = {{"version", version}, {"sha256", hashes}};
    write_file_atomic(kNumericsGoldenFile, golden.dump(2) + "\n");
    std::printf("wrote the %s golden (%s) into %s\n", backend.c_str(), version.c_str(), kNumericsGoldenFile.c_str());
    return;
  }
  const Json golden = read_json_file(kNumericsGoldenFile);
  ASSERT_TRUE(golden.contains(backend)) << kNumericsGoldenFile << " has no " << backend << " golden: make it with "
                                        << kRegenerateNumericsGolden;
  const std::string made_under = golden.at(backend).at("version");
  ASSERT_EQ(made_under, version) << "the " << backend << " golden was made under numerics version " << made_under
                                 << ", the code is " << version << ": regenerate it with " << kRegenerateNumericsGolden;
  const Json& want = golden.at(backend).at("sha256");
  for (const auto& [name, sha] : hashes) {
    ASSERT_TRUE(want.contains(name)) << "no golden for case " << name << ": regenerate with " << kRegenerateNumericsGolden;
    EXPECT_EQ(sha, want.at(name).get<std::string>())
        << "case " << name << ": the trained bits changed while the numerics version stayed " << version
        << ". Results trained before and after would pass for one recipe: bump " << constant
        << " and regenerate the golden with " << kRegenerateNumericsGolden;
  }
  EXPECT_EQ(want.size(), hashes.size()) << "the golden holds cases this test no longer trains: regenerate it with "
                                        << kRegenerateNumericsGolden;
}

}  // namespace weathergs::testing
