// One benchmark, bit for bit: the deterministic SIFT matcher, and `weathergs generate` giving the
// same dataset identity with 1 and 2 threads from fresh caches, equal to the committed expected one,
// and refusing (or, when allowed, recording) a dataset that differs from it.
#include <gtest/gtest.h>

#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/dataset_identity.h"
#include "core/json_reader.h"
#include "core/parallel.h"
#include "capture/expected_identity.h"
#include "capture/process.h"
#include "capture/sift_keypoints.h"
#include "capture/sift_matcher.h"
#include "tests/core/test_util.h"

namespace weathergs::capture {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;

// A random unit descriptor scaled to 512 and clamped to bytes, as COLMAP stores them.
std::vector<uint8_t> random_descriptor(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  std::vector<double> v(128);
  double norm = 0;
  for (double& x : v) x = std::abs(n(rng)), norm += x * x;
  std::vector<uint8_t> out(128);
  for (int i = 0; i < 128; ++i) out[size_t(i)] = uint8_t(std::min(255.0, std::round(512.0 * v[size_t(i)] / std::sqrt(norm))));
  return out;
}

SiftDescriptors make(const std::vector<std::vector<uint8_t>>& rows) {
  SiftDescriptors d;
  d.rows = int(rows.size());
  for (const auto& r : rows) d.data.insert(d.data.end(), r.begin(), r.end());
  return d;
}

// A perturbed copy: a true correspondence seen again.
std::vector<uint8_t> jitter(const std::vector<uint8_t>& d, std::mt19937& rng, int amount) {
  std::uniform_int_distribution<int> u(-amount, amount);
  std::vector<uint8_t> out = d;
  for (uint8_t& x : out) x = uint8_t(std::clamp(int(x) + u(rng), 0, 255));
  return out;
}

// COLMAP's rule evaluated in double precision, one way: the best column when it passes both tests.
int reference_best(const SiftDescriptors& a, int i, const SiftDescriptors& b, const SiftMatchOptions& o) {
  double d1 = 0, d2 = 0;
  int j1 = -1;
  for (int j = 0; j < b.rows; ++j) {
    double dot = 0;
    for (int k = 0; k < 128; ++k) dot += double(a.data[size_t(i * 128 + k)]) * double(b.data[size_t(j * 128 + k)]);
    if (dot > d1) d2 = d1, d1 = dot, j1 = j;
    else if (dot > d2) d2 = dot;
  }
  auto angle = [](double dot) { return std::acos(std::min(dot / (512.0 * 512.0), 1.0)); };
  if (j1 < 0 || angle(d1) > o.max_distance || angle(d1) >= o.max_ratio * angle(d2)) return -1;
  return j1;
}

TEST(SiftMatcherTest, MutualNearestNeighboursByColmapsRule) {
  std::mt19937 rng(3);
  std::vector<std::vector<uint8_t>> a, b;
  for (int i = 0; i < 60; ++i) a.push_back(random_descriptor(rng));
  // b: jittered copies of the first 40 of a (in reverse order), then 30 unrelated descriptors.
  for (int i = 39; i >= 0; --i) b.push_back(jitter(a[size_t(i)], rng, 3));
  for (int i = 0; i < 30; ++i) b.push_back(random_descriptor(rng));
  const SiftDescriptors da = make(a), db = make(b);
  const SiftMatchOptions o;
  const auto m = match_sift_descriptors(da, db, o);
  std::map<int, int> found(m.begin(), m.end());
  for (int i = 0; i < 40; ++i) {
    ASSERT_TRUE(found.count(i)) << "a true correspondence was lost: " << i;
    EXPECT_EQ(found[i], 39 - i);
  }
  // Exactly the pairs the rule keeps, computed independently in double precision.
  for (int i = 0; i < da.rows; ++i) {
    const int j = reference_best(da, i, db, o);
    const bool mutual = j >= 0 && reference_best(db, j, da, o) == i;
    EXPECT_EQ(found.count(i) > 0, mutual) << i;
    if (mutual) {
      EXPECT_EQ(found[i], j);
    }
  }
  for (size_t k = 1; k < m.size(); ++k) EXPECT_LT(m[k - 1].first, m[k].first);
}

TEST(SiftMatcherTest, AmbiguousAndOneSidedMatchesAreRejected) {
  std::mt19937 rng(5);
  const auto x = random_descriptor(rng), y = random_descriptor(rng);
  // x appears twice in b: best == second best, so the ratio test (>=) rejects it, as COLMAP does.
  auto m = match_sift_descriptors(make({x}), make({x, x}), SiftMatchOptions{});
  EXPECT_TRUE(m.empty());
  // a = {x, x'} both nearest to b's single x: b's x picks one of them (the lower index on a tie),
  // and cross-checking keeps only that one.
  m = match_sift_descriptors(make({x, x, y}), make({x, y}), SiftMatchOptions{[] {
                               SiftMatchOptions o;
                               o.max_ratio = 1.0;  // let the duplicate pass the ratio test
                               return o;
                             }()});
  ASSERT_EQ(m.size(), 1u);  // x is ambiguous on a's side even at ratio 1 (>=), y matches y
  EXPECT_EQ(m[0], std::make_pair(2, 1));
  // A far descriptor (angle above max_distance) is no match even if it is the only one.
  std::vector<uint8_t> z(128, 0);
  z[0] = 255;
  SiftMatchOptions strict;
  strict.max_distance = 0.1;
  EXPECT_TRUE(match_sift_descriptors(make({x}), make({z}), strict).empty());
}

struct Keypoint {
  float x = 300, y = 200, scale = 2.7f;  // COLMAP's coordinates, on a 600 x 400 camera
};

void insert_blob(sqlite3* db, const char* sql, int id, int rows, const void* data, int bytes) {
  sqlite3_stmt* st = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db, sql, -1, &st, nullptr), SQLITE_OK);
  sqlite3_bind_int(st, 1, id);
  sqlite3_bind_int(st, 2, rows);
  sqlite3_bind_blob(st, 3, data, bytes, SQLITE_TRANSIENT);
  ASSERT_EQ(sqlite3_step(st), SQLITE_DONE);
  sqlite3_finalize(st);
}

// A COLMAP-like database with the tables the matcher reads; keypoints[i] places image i's keypoints
// (all at the centre where it is missing), stored as COLMAP's affine (x, y, a11, a12, a21, a22).
void write_database(const std::string& path, const std::vector<SiftDescriptors>& images,
                    const std::vector<std::vector<Keypoint>>& keypoints = {}) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db,
                         "CREATE TABLE images (image_id INTEGER PRIMARY KEY, name TEXT, camera_id INTEGER);"
                         "CREATE TABLE cameras (camera_id INTEGER PRIMARY KEY, width INTEGER, height INTEGER);"
                         "INSERT INTO cameras VALUES (1, 600, 400);"
                         "CREATE TABLE keypoints (image_id INTEGER PRIMARY KEY, rows INTEGER, cols INTEGER, data BLOB);"
                         "CREATE TABLE descriptors (image_id INTEGER PRIMARY KEY, rows INTEGER, cols INTEGER, data BLOB);",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  for (size_t i = 0; i < images.size(); ++i) {
    // Image ids out of name order, as COLMAP's threaded extraction gives them.
    const int id = int(images.size() - i);
    const std::string sql = "INSERT INTO images VALUES (" + std::to_string(id) + ", 'v" + std::to_string(i) + ".png', 1);";
    ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
    insert_blob(db, "INSERT INTO descriptors VALUES (?, ?, 128, ?);", id, images[i].rows, images[i].data.data(),
                int(images[i].data.size()));
    std::vector<float> k;
    for (int r = 0; r < images[i].rows; ++r) {
      const Keypoint p = i < keypoints.size() && size_t(r) < keypoints[i].size() ? keypoints[i][size_t(r)] : Keypoint{};
      k.insert(k.end(), {p.x, p.y, p.scale, 0.f, 0.f, p.scale});
    }
    insert_blob(db, "INSERT INTO keypoints VALUES (?, ?, 6, ?);", id, images[i].rows, k.data(), int(k.size() * sizeof(float)));
  }
  sqlite3_close(db);
}

TEST(SiftMatcherTest, MatchListIsTheSameWithOneAndTwoThreads) {
  TempDir tmp;
  std::mt19937 rng(11);
  std::vector<std::vector<uint8_t>> base;
  for (int i = 0; i < 300; ++i) base.push_back(random_descriptor(rng));
  std::vector<SiftDescriptors> images;
  for (int v = 0; v < 6; ++v) {
    std::vector<std::vector<uint8_t>> rows;
    for (int i = 0; i < 300; ++i)
      if ((i + v) % 3 != 0) rows.push_back(jitter(base[size_t(i)], rng, 4));  // each view sees 2/3 of the points
    images.push_back(make(rows));
  }
  const std::string db = tmp / "database.db";
  write_database(db, images);
  const int before = num_threads();
  set_num_threads(1);
  const int64_t n1 = write_exhaustive_match_list(db, tmp / "m1.txt", SiftMatchOptions{});
  set_num_threads(2);
  const int64_t n2 = write_exhaustive_match_list(db, tmp / "m2.txt", SiftMatchOptions{});
  set_num_threads(before);
  EXPECT_EQ(n1, n2);
  EXPECT_GT(n1, 15 * 80);  // 15 pairs, ~100 points seen by both views of a pair
  EXPECT_EQ(read_file(tmp / "m1.txt"), read_file(tmp / "m2.txt"));
  // Pairs in increasing image id: image 1 is v5.png, so the first block is "v5.png v4.png".
  EXPECT_EQ(read_file(tmp / "m1.txt").rfind("v5.png v4.png\n", 0), 0u);
}

// Keypoints measured in paper pool_rain (600 x 400): the first two are on octave 0's last row, and
// their stored descriptors differed in each of five extractions of the same images; the third, found
// in octave 0, repeated in all five, while octave 1 would have refused it.
TEST(SiftKeypointsTest, TheDescriptorStepRefusesAnOctavesLastRow) {
  EXPECT_TRUE(sift_descriptor_unwritten(394.59634, 399.18218, 0, 600, 400));
  EXPECT_TRUE(sift_descriptor_unwritten(219.00104, 399.09445, 0, 600, 400));
  EXPECT_FALSE(sift_descriptor_unwritten(410.73044, 397.7337, 0, 600, 400));
  EXPECT_TRUE(sift_descriptor_unwritten(410.73044, 397.7337, 1, 600, 400));
  EXPECT_FALSE(sift_descriptor_unwritten(300, 200, 0, 600, 400));
  EXPECT_FALSE(sift_descriptor_unwritten(394.6, 398.5, 0, 600, 400));  // a row above: written
  // The upsampled octave -1 refuses only its own last row.
  EXPECT_TRUE(sift_descriptor_unwritten(100, 399.9, -1, 600, 400));
  EXPECT_FALSE(sift_descriptor_unwritten(100, 399.4, -1, 600, 400));
}

// One image's keypoints as COLMAP's CPU extraction stores them: octave by octave, level by level,
// each level scanned from the top row down; `extra` is appended to the scan of (octave, level).
struct ExtraKeypoint {
  int octave, level;
  float x, y, scale;
};
std::vector<float> extraction_order(const ExtraKeypoint& extra, int* extra_index) {
  const double sigma0 = 1.6 * std::pow(2.0, 1.0 / 3.0);
  std::vector<float> k;
  for (int o = -1; o <= 2; ++o)
    for (int l = 0; l < 3; ++l) {
      const int n = 40 >> (o + 1);  // fewer keypoints in coarser octaves
      for (int i = 0; i < n; ++i) {
        // Refined levels up to 0.4 from the detection level; rows from the top down.
        const float scale = float(sigma0 * std::pow(2.0, o + (l + 0.4 * std::sin(i)) / 3.0));
        k.insert(k.end(), {float(50 + 13 * i % 500), float(5 + 390.0 * i / n), scale, 0.f, 0.f, scale});
      }
      if (o == extra.octave && l == extra.level) {
        *extra_index = int(k.size() / 6);
        k.insert(k.end(), {extra.x, extra.y, extra.scale, 0.f, 0.f, extra.scale});
      }
    }
  return k;
}

// Measured in paper tanabata_rain: a keypoint on the last row at scale 2.195 is level 0.37 of octave 0
// or level 3.37 of octave -1. Its stored bytes differed between two extractions: found in octave 0,
// whose last row it is on. The stored order says which octave: the same keypoint at the end of
// octave -1's top level is written.
TEST(SiftKeypointsTest, TheOctaveComesFromTheStoredOrder) {
  int index = -1;
  std::vector<float> k = extraction_order({0, 0, 388.46f, 399.124f, 2.195f}, &index);
  const int rows = int(k.size() / 6);
  std::vector<int> octaves = sift_keypoint_octaves(k.data(), rows, 6);
  ASSERT_EQ(int(octaves.size()), rows);
  EXPECT_EQ(octaves[size_t(index)], 0);
  EXPECT_EQ(octaves.front(), -1);
  EXPECT_EQ(octaves.back(), 2);
  EXPECT_TRUE(std::is_sorted(octaves.begin(), octaves.end()));
  EXPECT_TRUE(sift_descriptors_unwritten(k.data(), rows, 6, 600, 400)[size_t(index)]);

  k = extraction_order({-1, 2, 388.46f, 399.124f, 2.195f}, &index);
  octaves = sift_keypoint_octaves(k.data(), rows, 6);
  ASSERT_EQ(int(octaves.size()), rows);
  EXPECT_EQ(octaves[size_t(index)], -1);
  EXPECT_FALSE(sift_descriptors_unwritten(k.data(), rows, 6, 600, 400)[size_t(index)]);
  // No other keypoint of the list is on a last row.
  const std::vector<bool> unwritten = sift_descriptors_unwritten(k.data(), rows, 6, 600, 400);
  EXPECT_EQ(std::count(unwritten.begin(), unwritten.end(), true), 0);
}

// A list in no extraction's order (a coarse level before a fine one) has no octaves; then a keypoint
// counts as unwritten only when every octave its scale allows would refuse it.
TEST(SiftKeypointsTest, OutOfOrderKeypointsFallBackToEveryPossibleOctave) {
  const std::vector<float> k = {300, 200, 16.f, 0, 0, 16.f,               // octave 2
                                300, 200, 1.2f, 0, 0, 1.2f,               // octave -1 only
                                388.46f, 399.124f, 2.195f, 0, 0, 2.195f,  // octave -1 or 0
                                100, 399.9f, 1.2f, 0, 0, 1.2f};           // octave -1, last row
  EXPECT_TRUE(sift_keypoint_octaves(k.data(), 4, 6).empty());
  EXPECT_EQ(sift_descriptors_unwritten(k.data(), 4, 6, 600, 400), std::vector<bool>({false, false, false, true}));
  EXPECT_TRUE(sift_keypoint_octaves(k.data(), 0, 6).empty());
}

TEST(SiftMatcherTest, AKeypointWithAnUnwrittenDescriptorNeverMatches) {
  TempDir tmp;
  std::mt19937 rng(13);
  std::vector<std::vector<uint8_t>> rows;
  for (int i = 0; i < 20; ++i) rows.push_back(random_descriptor(rng));
  const std::vector<SiftDescriptors> images = {make(rows), make(rows)};
  write_database(tmp / "centre.db", images);
  // Keypoint 0 of the second image on octave 0's last row; its descriptor is unchanged.
  write_database(tmp / "edge.db", images, {{}, {Keypoint{394.59634f, 399.18218f, 2.72f}}});
  EXPECT_EQ(write_exhaustive_match_list(tmp / "centre.db", tmp / "centre.txt", SiftMatchOptions{}), 20);
  EXPECT_EQ(write_exhaustive_match_list(tmp / "edge.db", tmp / "edge.txt", SiftMatchOptions{}), 19);
  EXPECT_EQ(read_file(tmp / "edge.txt").find("\n0 0\n"), std::string::npos);
  EXPECT_NE(read_file(tmp / "edge.txt").find("\n1 1\n"), std::string::npos);
}

bool have_tools() { return !find_executable("blender").empty() && !find_executable("colmap").empty(); }

std::string scenes_dir() { return std::string(WEATHERGS_SOURCE_DIR) + "/scenes"; }

Json dataset_json(const std::string& dir) { return Json::parse(read_file(dir + "/dataset.json")); }

std::string generate_command(const std::string& scene, int threads, const std::string& cache, const std::string& out,
                             const std::string& extra = "") {
  return std::string(WEATHERGS_BINARY) + " --threads " + std::to_string(threads) + " generate --scene " + scene +
         " --weather rain --profile tiny --cache " + cache + " --out " + out + " " + extra;
}

// Generating twice into fresh caches, with 1 and with 2 threads, gives one identity, and it is the
// committed one (scenes/expected/tiny.json): the bytes are those of every other machine.
TEST(GenerateIdentityTest, TinyVariantIsTheSameDatasetWithOneAndTwoThreadsAndMatchesTheCommittedOne) {
  if (!have_tools()) GTEST_SKIP() << "blender or colmap not installed";
  TempDir tmp;
  const std::string scene = scenes_dir() + "/pool.json";
  for (int threads : {1, 2}) {
    const std::string out = tmp / ("pool_rain_" + std::to_string(threads));
    const auto r = testing::run_command(generate_command(scene, threads, tmp / ("cache" + std::to_string(threads)), out));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("(matches)"), std::string::npos) << r.output;
  }
  const Json a = dataset_json(tmp / "pool_rain_1"), b = dataset_json(tmp / "pool_rain_2");
  EXPECT_EQ(a["identity"]["sha256"], b["identity"]["sha256"]);
  EXPECT_EQ(a["generator"]["identity_check"]["result"], "matches");
  // The recorded identity is the files' identity now.
  EXPECT_EQ(compute_dataset_identity(tmp / "pool_rain_1").sha256, a["identity"]["sha256"].get<std::string>());
  // Every covered file is the same, not only the hash over them.
  const DatasetIdentity ia = compute_dataset_identity(tmp / "pool_rain_1"), ib = compute_dataset_identity(tmp / "pool_rain_2");
  EXPECT_EQ(first_difference(ia, ib), std::nullopt);
  EXPECT_GT(ia.files.size(), 30u);
  // The restoration targets add targets/ and change nothing else: such a dataset is compared on the
  // files both have, and matches (the workflow generates with --targets).
  const auto r = testing::run_command(generate_command(scene, 2, tmp / "cache1", tmp / "with_targets", "--targets"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("(matches)"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::is_directory(tmp / "with_targets/targets"));
}

// A dataset that is not the benchmark's is refused, naming the variant, the tools and the first
// differing file; --allow-identity-mismatch keeps it and says so in its dataset.json.
TEST(GenerateIdentityTest, ADifferentDatasetIsRefusedUnlessAllowed) {
  if (!have_tools()) GTEST_SKIP() << "blender or colmap not installed";
  TempDir tmp;
  // The scene beside an expected file whose sparse/0 points differ by one hash.
  fs::create_directories(tmp / "scenes/expected");
  fs::copy_file(scenes_dir() + "/pool.json", tmp / "scenes/pool.json");
  Json expected = Json::parse(read_file(scenes_dir() + "/expected/tiny.json"));
  Json& files = expected["variants"]["pool_rain"]["identity"]["files"];
  ASSERT_TRUE(files.contains("sparse/0/points3D.txt"));
  files["sparse/0/points3D.txt"] = std::string(64, '0');
  expected["variants"]["pool_rain"]["identity"]["sha256"] = std::string(64, 'f');
  write_file_atomic(tmp / "scenes/expected/tiny.json", expected.dump(1));
  const std::string scene = tmp / "scenes/pool.json";
  auto r = testing::run_command(generate_command(scene, 2, tmp / "cache", tmp / "refused"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("pool_rain (tiny profile) is not the benchmark's dataset"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("first difference: sparse/0/points3D.txt differs"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("found Blender 3.4.1, COLMAP 3.8"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(tmp / "refused")) << "a refused dataset is not left behind";
  EXPECT_EQ(r.output.find("cache entry"), std::string::npos) << "the render is not at fault here: " << r.output;
  r = testing::run_command(generate_command(scene, 2, tmp / "cache", tmp / "kept", "--allow-identity-mismatch"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Json check = dataset_json(tmp / "kept")["generator"]["identity_check"];
  EXPECT_EQ(check["result"], "mismatch allowed");
  EXPECT_EQ(check["first_difference"], "sparse/0/points3D.txt differs");
  // A clean view that differs: the cached render is named, since every later run would reuse it.
  files["clean/000.png"] = std::string(64, '0');
  write_file_atomic(tmp / "scenes/expected/tiny.json", expected.dump(1));
  r = testing::run_command(generate_command(scene, 2, tmp / "cache", tmp / "refused"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("first difference: clean/000.png differs"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("The clean render comes from the cache entry " + std::string(tmp / "cache")), std::string::npos)
      << r.output;
  // Other settings than the expected entry's (another weather seed) are not checked, and say so.
  r = testing::run_command(generate_command(scene, 2, tmp / "cache", tmp / "seed8", "--seed 8"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(dataset_json(tmp / "seed8")["generator"]["identity_check"]["result"],
            "not checked: other settings than the expected identity's");
}

}  // namespace
}  // namespace weathergs::capture
