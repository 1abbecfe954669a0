// A dataset's identity: one SHA-256 over everything a method reads or is scored against, so that two
// runs are known to have seen the same bytes (docs/formats.md, "Dataset identity").
//
// The identity covers, by path relative to the dataset root: cameras.json, transforms.json, every
// file under images/, clean/, depth/, masks/, targets/, sparse/0/ and sparse_clean/0/, and the part
// of dataset.json a method reads (name, scene, weather, splits, splits_rule) as the canonical
// pseudo-file "dataset.json#splits". It leaves out logs/ (tool logs), layers/ (float layers the
// generator rebuilds from the files above) and the rest of dataset.json (timings, provenance).
// Each file's SHA-256 is taken over its bytes; the identity is the SHA-256 of the lines
// "<path> <file sha256>\n" in byte order of the paths.
#pragma once

#include <map>
#include <optional>
#include <string>

#include "core/json_reader.h"

namespace weathergs {

struct DatasetIdentity {
  // The scheme's name, bumped whenever what is covered or how it is hashed changes.
  static constexpr const char* kScheme = "weathergs-dataset-identity-v1";
  std::string sha256;
  std::map<std::string, std::string> files;  // relative path -> SHA-256 of its bytes

  Json to_json(bool with_files) const;  // {scheme, sha256, file_count[, files]}
  // Reads what to_json wrote; InputError naming `r` on another scheme or a malformed block.
  static DatasetIdentity from_json(const JsonReader& r);
};

// The identity of these files (path -> SHA-256): the one rule that turns per-file hashes into one.
DatasetIdentity identity_of_files(std::map<std::string, std::string> files);

// Hashes the dataset's files now (InputError if root is not a dataset folder).
DatasetIdentity compute_dataset_identity(const std::string& root);

// Hashes the dataset's files and writes the identity, with its files, into its dataset.json
// (atomically): what every step that makes or changes a dataset's covered files calls last.
DatasetIdentity record_dataset_identity(const std::string& root);

// The first path, in path order, whose hash differs or that only one side has, with a description
// ("images/003.png differs", "sparse/0/points3D.txt is missing", "masks/lens/000.png is extra");
// nullopt when both hold the same files. `found` is the dataset at hand, `expected` the reference.
std::optional<std::string> first_difference(const DatasetIdentity& found, const DatasetIdentity& expected);

}  // namespace weathergs
