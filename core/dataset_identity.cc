#include "core/dataset_identity.h"

#include <algorithm>
#include <filesystem>

#include "core/dataset.h"
#include "core/dataset_layout.h"
#include "core/error.h"
#include "core/sha256.h"

namespace weathergs {

namespace fs = std::filesystem;

namespace {

// Folders whose every file is covered, relative to the root.
constexpr const char* kCoveredDirs[] = {layout::kImagesDir, layout::kCleanDir,       layout::kDepthDir, "masks",
                                        "targets",          layout::kSparseModelDir, layout::kSparseCleanModelDir};
constexpr const char* kCoveredFiles[] = {layout::kCamerasJson, layout::kTransformsJson};
constexpr const char* kSplitsPseudoFile = "dataset.json#splits";

std::string canonical_splits(const DatasetInfo& info) {
  Json j = {{"name", info.name}, {"scene", info.scene}, {"weather", info.weather}, {"splits", info.splits}};
  if (info.splits_rule) j["splits_rule"] = *info.splits_rule;
  return j.dump();  // nlohmann's objects are ordered by key: one spelling for one content
}

}  // namespace

Json DatasetIdentity::to_json(bool with_files) const {
  Json j = {{"scheme", kScheme}, {"sha256", sha256}, {"file_count", files.size()}};
  if (with_files) j["files"] = files;
  return j;
}

DatasetIdentity DatasetIdentity::from_json(const JsonReader& r) {
  if (!r.is_object()) throw InputError(r.where(), "expected a dataset identity {scheme, sha256, file_count[, files]}");
  const std::string scheme = r.get<std::string>("scheme");
  if (scheme != kScheme)
    throw InputError(r.where("scheme"), "unknown identity scheme \"" + scheme + "\" (this build knows \"" + kScheme + "\")");
  DatasetIdentity id;
  id.sha256 = r.get<std::string>("sha256");
  if (id.sha256.size() != 64) throw InputError(r.where("sha256"), "expected 64 hex digits");
  const size_t count = r.get<size_t>("file_count");
  if (r.has("files")) {
    const JsonReader files = r.child("files");
    if (!files.is_object()) throw InputError(files.where(), "expected an object of path -> sha256");
    for (const std::string& k : files.keys()) id.files[k] = files.get<std::string>(k);
    if (id.files.size() != count)
      throw InputError(r.where("file_count"), "says " + std::to_string(count) + " files, files lists " +
                                                  std::to_string(id.files.size()));
  }
  r.finish();
  return id;
}

DatasetIdentity compute_dataset_identity(const std::string& root) {
  const DatasetInfo info = read_dataset_json((fs::path(root) / layout::kDatasetJson).string());
  DatasetIdentity id;
  for (const char* f : kCoveredFiles) {
    const fs::path p = fs::path(root) / f;
    if (fs::is_regular_file(p)) id.files[f] = sha256_file(p.string());
  }
  for (const char* d : kCoveredDirs) {
    const fs::path dir = fs::path(root) / d;
    if (!fs::is_directory(dir)) continue;
    for (const auto& e : fs::recursive_directory_iterator(dir)) {
      if (!e.is_regular_file()) continue;
      id.files[fs::relative(e.path(), root).generic_string()] = sha256_file(e.path().string());
    }
  }
  id.files[kSplitsPseudoFile] = sha256_hex(canonical_splits(info));
  return identity_of_files(std::move(id.files));
}

DatasetIdentity identity_of_files(std::map<std::string, std::string> files) {
  DatasetIdentity id;
  id.files = std::move(files);
  Sha256 h;
  for (const auto& [path, sha] : id.files) h.update(path + " " + sha + "\n");  // std::map: byte order of paths
  id.sha256 = h.hex_digest();
  return id;
}

DatasetIdentity record_dataset_identity(const std::string& root) {
  const std::string path = (fs::path(root) / layout::kDatasetJson).string();
  DatasetInfo info = read_dataset_json(path);
  const DatasetIdentity id = compute_dataset_identity(root);
  info.identity = id.to_json(true);
  write_dataset_json(path, info);
  return id;
}

std::optional<std::string> first_difference(const DatasetIdentity& found, const DatasetIdentity& expected) {
  auto f = found.files.begin(), e = expected.files.begin();
  while (f != found.files.end() || e != expected.files.end()) {
    if (e == expected.files.end() || (f != found.files.end() && f->first < e->first)) return f->first + " is extra";
    if (f == found.files.end() || e->first < f->first) return e->first + " is missing";
    if (f->second != e->second) return f->first + " differs";
    ++f, ++e;
  }
  if (found.sha256 != expected.sha256) return std::string("the identity differs with the same files (another scheme?)");
  return std::nullopt;
}

}  // namespace weathergs
