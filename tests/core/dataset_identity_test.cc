// A dataset's identity (core/dataset_identity.h): one hash over every file a method reads or is
// scored against, stable, moved by any byte of them and by nothing else.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/dataset_identity.h"
#include "tests/core/test_util.h"

namespace weathergs {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// Every file the identity covers, one of each kind, relative to the root (contents are arbitrary
// bytes: the identity hashes bytes, it does not decode them).
const char* kCovered[] = {"cameras.json",           "transforms.json",           "images/000.png",
                          "clean/000.png",          "depth/000.exr",             "masks/lens/000.png",
                          "masks/particles/000.png", "targets/no_particles/000.png", "targets/lens_only/000.png",
                          "sparse/0/points3D.txt",  "sparse_clean/0/cameras.txt"};

Dataset make_dataset(const std::string& root) {
  Dataset d;
  d.root = root;
  std::vector<std::string> names;
  for (int i = 0; i < 3; ++i) {
    Camera c;
    c.name = "00" + std::to_string(i);
    c.width = 8;
    c.height = 6;
    c.fx = c.fy = 8;
    c.cx = 4;
    c.cy = 3;
    c.exposure_s = 1.0 / 60;
    d.cameras.push_back(c);
    names.push_back(c.name);
  }
  d.info.name = "toy_rain";
  d.info.scene = "toy";
  d.info.weather = "rain";
  d.info.splits = llff_splits(names);
  d.info.splits_rule = kLlffSplitRule;
  write_dataset(d);
  for (const char* f : kCovered) {
    if (std::string(f) == "cameras.json") continue;  // written by write_dataset
    fs::create_directories((fs::path(root) / f).parent_path());
    write_file_atomic((fs::path(root) / f).string(), std::string("bytes of ") + f);
  }
  return d;
}

// Flips the bits of one byte of a file, in place.
void flip_byte(const std::string& path, size_t at) {
  std::string bytes = read_file(path);
  ASSERT_LT(at, bytes.size()) << path;
  bytes[at] = char(~bytes[at]);
  write_file_atomic(path, bytes);
}

TEST(DatasetIdentity, StableAndIndependentOfWhereTheDatasetLies) {
  TempDir a, b;
  make_dataset(a.path());
  const DatasetIdentity id = compute_dataset_identity(a.path());
  EXPECT_EQ(id.sha256.size(), 64u);
  EXPECT_EQ(id.files.size(), std::size(kCovered) + 1) << "the covered files and dataset.json#splits";
  EXPECT_TRUE(id.files.count("dataset.json#splits"));
  EXPECT_EQ(compute_dataset_identity(a.path()).sha256, id.sha256);
  copy_tree(a.path(), b / "elsewhere");
  const DatasetIdentity moved = compute_dataset_identity(b / "elsewhere");
  EXPECT_EQ(moved.sha256, id.sha256);
  EXPECT_EQ(first_difference(moved, id), std::nullopt);
}

TEST(DatasetIdentity, OneByteOfAnyCoveredFileChangesItAndIsNamed) {
  TempDir dir;
  make_dataset(dir.path());
  const DatasetIdentity before = compute_dataset_identity(dir.path());
  for (const char* f : kCovered) {
    const std::string path = (fs::path(dir.path()) / f).string();
    const std::string original = read_file(path);
    flip_byte(path, original.size() / 2);
    const DatasetIdentity after = compute_dataset_identity(dir.path());
    EXPECT_NE(after.sha256, before.sha256) << f;
    EXPECT_EQ(first_difference(after, before), std::string(f) + " differs");
    write_file_atomic(path, original);
  }
  EXPECT_EQ(compute_dataset_identity(dir.path()).sha256, before.sha256) << "restored";
}

TEST(DatasetIdentity, SplitsAndNamesCountTheRestOfDatasetJsonDoesNot) {
  TempDir dir;
  Dataset d = make_dataset(dir.path());
  const DatasetIdentity before = compute_dataset_identity(dir.path());
  // Not covered: tool logs, the float layers, and dataset.json's provenance (including the identity
  // itself, so that recording it does not change it).
  fs::create_directories(dir / "logs");
  write_file_atomic(dir / "logs/colmap.log", "a log");
  fs::create_directories(dir / "layers/lens_coverage");
  write_file_atomic(dir / "layers/lens_coverage/000.exr", "a layer");
  d.info.generator = Json{{"version", "x"}, {"seconds", 12.5}};
  d.info.source = Json{{"video", "clip.mp4"}};
  d.info.identity = before.to_json(true);
  write_dataset_json(dir / "dataset.json", d.info);
  EXPECT_EQ(compute_dataset_identity(dir.path()).sha256, before.sha256);
  // The recorded identity survives a round trip through dataset.json.
  const DatasetInfo back = read_dataset_json(dir / "dataset.json");
  ASSERT_TRUE(back.identity);
  EXPECT_EQ(DatasetIdentity::from_json(JsonReader(*back.identity, "dataset.json", "/identity")).files, before.files);
  // Covered: the splits, and a file's name as well as its bytes.
  std::swap(d.info.splits["train"].front(), d.info.splits["test"].front());
  write_dataset_json(dir / "dataset.json", d.info);
  DatasetIdentity changed = compute_dataset_identity(dir.path());
  EXPECT_NE(changed.sha256, before.sha256);
  EXPECT_EQ(first_difference(changed, before), "dataset.json#splits differs");
  std::swap(d.info.splits["train"].front(), d.info.splits["test"].front());
  write_dataset_json(dir / "dataset.json", d.info);
  EXPECT_EQ(compute_dataset_identity(dir.path()).sha256, before.sha256);
  fs::rename(dir / "images/000.png", dir / "images/001.png");
  changed = compute_dataset_identity(dir.path());
  EXPECT_NE(changed.sha256, before.sha256);
  EXPECT_EQ(first_difference(changed, before), "images/000.png is missing");
  EXPECT_EQ(first_difference(before, changed), "images/000.png is extra");
}

TEST(DatasetIdentity, FirstDifferenceIsTheFirstPathInOrder) {
  DatasetIdentity a, b;
  a.files = {{"clean/000.png", "1"}, {"images/000.png", "2"}, {"images/001.png", "3"}};
  b.files = a.files;
  a.sha256 = b.sha256 = std::string(64, 'a');
  EXPECT_EQ(first_difference(a, b), std::nullopt);
  b.files["images/001.png"] = "4";
  b.files["masks/lens/000.png"] = "5";
  EXPECT_EQ(first_difference(a, b), "images/001.png differs");
  b.files["clean/000.png"] = "6";
  EXPECT_EQ(first_difference(a, b), "clean/000.png differs");
  b.files = a.files;
  b.files["depth/000.exr"] = "7";
  EXPECT_EQ(first_difference(a, b), "depth/000.exr is missing");
  b.files = a.files;
  b.sha256 = std::string(64, 'b');
  EXPECT_NE(first_difference(a, b), std::nullopt) << "same files, other identity: still different";
}

TEST(DatasetIdentity, JsonRoundTripAndStrictReading) {
  TempDir dir;
  make_dataset(dir.path());
  const DatasetIdentity id = compute_dataset_identity(dir.path());
  const Json with = id.to_json(true), without = id.to_json(false);
  EXPECT_EQ(with.at("scheme"), DatasetIdentity::kScheme);
  EXPECT_EQ(with.at("file_count"), id.files.size());
  EXPECT_FALSE(without.contains("files"));
  const DatasetIdentity back = DatasetIdentity::from_json(JsonReader(with, "x.json"));
  EXPECT_EQ(back.sha256, id.sha256);
  EXPECT_EQ(back.files, id.files);
  EXPECT_EQ(DatasetIdentity::from_json(JsonReader(without, "x.json")).sha256, id.sha256);
  auto error = [](const Json& j) {
    try {
      DatasetIdentity::from_json(JsonReader(j, "x.json", "/identity"));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  Json bad = with;
  bad["scheme"] = "weathergs-dataset-identity-v0";
  EXPECT_NE(error(bad).find("x.json:/identity/scheme"), std::string::npos) << error(bad);
  EXPECT_NE(error(bad).find("unknown identity scheme"), std::string::npos) << error(bad);
  bad = with;
  bad["sha256"] = "abc";
  EXPECT_NE(error(bad).find("64 hex digits"), std::string::npos) << error(bad);
  bad = with;
  bad["file_count"] = id.files.size() + 1;
  EXPECT_NE(error(bad).find("file_count"), std::string::npos) << error(bad);
  bad = without;
  bad["extra"] = 1;
  EXPECT_NE(error(bad).find("'extra'"), std::string::npos) << error(bad);
  EXPECT_NE(error(Json::array()).find("expected a dataset identity"), std::string::npos);
}

TEST(DatasetIdentity, NotADatasetIsBadInput) {
  TempDir dir;
  EXPECT_THROW(compute_dataset_identity(dir.path()), InputError);
}

}  // namespace
}  // namespace weathergs
