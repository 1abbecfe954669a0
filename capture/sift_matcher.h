// Deterministic exhaustive matching of the SIFT descriptors COLMAP extracted, in place of COLMAP
// 3.8's CPU exhaustive_matcher, which differs between runs on one database even with one thread
// (docs/determinism.md). The rule is COLMAP's own (SiftMatchingOptions: mutual nearest
// neighbours by descriptor angle, ratio 0.8, angle 0.7), computed so that every run on any machine
// gives the same matches: the dot products of the uint8 descriptors are sums of at most 128
// products <= 255^2, so they are exact integers below 2^24 in float32 whatever the summation order,
// and ties go to the lower feature index.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace weathergs::capture {

struct SiftMatchOptions {
  double max_ratio = 0.8;     // best angle < max_ratio x second-best angle (Lowe's ratio test)
  double max_distance = 0.7;  // best angle (radians, of the 512-normalised descriptors) at most this
  bool cross_check = true;    // keep only mutual nearest neighbours
  int max_num_matches = 32768;

  void validate() const;  // InputError naming the field
};

// One image's descriptors: rows x 128 bytes, row-major, as COLMAP stores them.
struct SiftDescriptors {
  int rows = 0;
  std::vector<uint8_t> data;
};

// Index pairs (into a, into b) in increasing index of a.
std::vector<std::pair<int, int>> match_sift_descriptors(const SiftDescriptors& a, const SiftDescriptors& b,
                                                        const SiftMatchOptions& options);

// Reads every image's descriptors from COLMAP's database, matches all pairs (image ids in increasing
// order, pairs spread over the process's threads, each written in its own slot) and writes COLMAP's raw
// match list for `colmap matches_importer --match_type raw`: "NAME1 NAME2", one "IDX1 IDX2" line per
// match, an empty line. Keypoints whose descriptor is unwritten (capture/sift_keypoints.h) take no
// part: they are nobody's best or second best. Returns the number of matches written.
int64_t write_exhaustive_match_list(const std::string& database_path, const std::string& match_list_path,
                                    const SiftMatchOptions& options);

}  // namespace weathergs::capture
