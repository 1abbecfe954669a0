#include "capture/sift_matcher.h"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <map>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/parallel.h"
#include "capture/colmap_database.h"
#include "capture/sift_keypoints.h"

namespace weathergs::capture {

namespace {

constexpr int kDim = 128;
// COLMAP's descriptors are unit vectors scaled by 512 and rounded to bytes; this turns a dot product
// back into a cosine.
constexpr double kDotToCosine = 1.0 / (512.0 * 512.0);

using Matrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

Matrix as_matrix(const SiftDescriptors& d) {
  Matrix m(d.rows, kDim);
  for (int64_t i = 0; i < int64_t(d.rows) * kDim; ++i) m.data()[i] = float(d.data[size_t(i)]);
  return m;
}

double angle(float dot) { return std::acos(std::min(double(dot) * kDotToCosine, 1.0)); }

// For each row of `dots`, the column of its largest entry (ties: the lower column) when it passes
// the distance and ratio tests, else -1.
std::vector<int> best_matches(const Matrix& dots, const SiftMatchOptions& o) {
  std::vector<int> best(size_t(dots.rows()), -1);
  for (Eigen::Index i = 0; i < dots.rows(); ++i) {
    float d1 = 0, d2 = 0;  // as COLMAP: a non-positive dot product is never a match
    int j1 = -1;
    for (Eigen::Index j = 0; j < dots.cols(); ++j) {
      const float d = dots(i, j);
      if (d > d1) {
        d2 = d1, d1 = d, j1 = int(j);
      } else if (d > d2) {
        d2 = d;
      }
    }
    if (j1 < 0) continue;
    const double a1 = angle(d1);
    if (a1 > o.max_distance) continue;
    if (a1 >= o.max_ratio * angle(d2)) continue;  // >=: equal best and second best is no match
    best[size_t(i)] = j1;
  }
  return best;
}

}  // namespace

void SiftMatchOptions::validate() const {
  const std::string where = "sift match options";
  if (!(max_ratio > 0 && max_ratio <= 1)) throw InputError(where, "max_ratio must be in (0, 1], is " + std::to_string(max_ratio));
  if (!(max_distance > 0 && max_distance <= M_PI))
    throw InputError(where, "max_distance must be in (0, pi], is " + std::to_string(max_distance));
  if (max_num_matches < 1) throw InputError(where, "max_num_matches must be >= 1");
}

std::vector<std::pair<int, int>> match_sift_descriptors(const SiftDescriptors& a, const SiftDescriptors& b,
                                                        const SiftMatchOptions& o) {
  WGS_CHECK_EQ(a.data.size(), size_t(a.rows) * kDim);
  WGS_CHECK_EQ(b.data.size(), size_t(b.rows) * kDim);
  std::vector<std::pair<int, int>> matches;
  if (a.rows == 0 || b.rows == 0) return matches;
  const Matrix ma = as_matrix(a), mb = as_matrix(b);
  // Exact: every product and partial sum is an integer below 2^24 (128 x 255^2 < 2^24).
  const Matrix dots = ma * mb.transpose();
  const std::vector<int> ab = best_matches(dots, o);
  std::vector<int> ba;
  if (o.cross_check) ba = best_matches(dots.transpose(), o);
  for (int i = 0; i < a.rows; ++i) {
    const int j = ab[size_t(i)];
    if (j < 0 || (o.cross_check && ba[size_t(j)] != i)) continue;
    matches.emplace_back(i, j);
    if (int(matches.size()) >= o.max_num_matches) break;
  }
  return matches;
}

int64_t write_exhaustive_match_list(const std::string& db_path, const std::string& list_path, const SiftMatchOptions& o) {
  o.validate();
  std::map<int, std::string> names;
  std::map<int, int> camera_of;
  std::map<int, std::pair<int, int>> sizes;  // camera id -> (width, height)
  std::map<int, SiftDescriptors> desc;
  const ColmapDatabase db(db_path);
  db.query("SELECT image_id, name, camera_id FROM images;", [&](sqlite3_stmt* st) {
    const unsigned char* name = sqlite3_column_text(st, 1);
    if (!name) throw InputError(db_path, "an image row without a name");
    names[sqlite3_column_int(st, 0)] = reinterpret_cast<const char*>(name);
    camera_of[sqlite3_column_int(st, 0)] = sqlite3_column_int(st, 2);
  });
  db.query("SELECT camera_id, width, height FROM cameras;", [&](sqlite3_stmt* st) {
    sizes[sqlite3_column_int(st, 0)] = {sqlite3_column_int(st, 1), sqlite3_column_int(st, 2)};
  });
  db.query("SELECT image_id, rows, cols, data FROM descriptors;", [&](sqlite3_stmt* st) {
    const int id = sqlite3_column_int(st, 0), rows = sqlite3_column_int(st, 1), cols = sqlite3_column_int(st, 2);
    if (cols != kDim && rows > 0)
      throw InputError(db_path, "descriptors of image " + std::to_string(id) + " have " + std::to_string(cols) +
                                    " columns, expected 128 (SIFT)");
    const auto* blob = static_cast<const uint8_t*>(sqlite3_column_blob(st, 3));
    const int bytes = sqlite3_column_bytes(st, 3);
    if (bytes != rows * kDim) throw InputError(db_path, "descriptor blob of image " + std::to_string(id) + " has the wrong size");
    SiftDescriptors& d = desc[id];
    d.rows = rows;
    d.data.assign(blob, blob + bytes);
  });
  // An unwritten descriptor becomes zeros: a non-positive dot product is never a match,
  // nor anyone's best or second best, so the keypoint is as if absent and the others match as before.
  db.query("SELECT image_id, rows, cols, data FROM keypoints;", [&](sqlite3_stmt* st) {
    const int id = sqlite3_column_int(st, 0), rows = sqlite3_column_int(st, 1), cols = sqlite3_column_int(st, 2);
    const auto d = desc.find(id);
    if (rows == 0 || d == desc.end()) return;
    if (rows != d->second.rows)
      throw InputError(db_path, "image " + std::to_string(id) + " has " + std::to_string(rows) + " keypoints and " +
                                    std::to_string(d->second.rows) + " descriptors");
    if (cols != 4 && cols != 6)
      throw InputError(db_path, "keypoints of image " + std::to_string(id) + " have " + std::to_string(cols) +
                                    " columns, expected 4 or 6 (SIFT with a scale)");
    if (sqlite3_column_bytes(st, 3) != rows * cols * int(sizeof(float)))
      throw InputError(db_path, "keypoint blob of image " + std::to_string(id) + " has the wrong size");
    const auto camera = sizes.find(camera_of.count(id) ? camera_of.at(id) : -1);
    if (camera == sizes.end()) throw InputError(db_path, "image " + std::to_string(id) + " has no camera row");
    std::vector<float> k(size_t(rows) * size_t(cols));
    std::memcpy(k.data(), sqlite3_column_blob(st, 3), k.size() * sizeof(float));
    const std::vector<bool> unwritten =
        sift_descriptors_unwritten(k.data(), rows, cols, camera->second.first, camera->second.second);
    for (int r = 0; r < rows; ++r)
      if (unwritten[size_t(r)]) std::fill_n(d->second.data.begin() + int64_t(r) * kDim, kDim, uint8_t(0));
  });
  std::vector<int> ids;
  for (const auto& [id, name] : names) ids.push_back(id);
  std::vector<std::pair<int, int>> pairs;
  for (size_t i = 0; i < ids.size(); ++i)
    for (size_t j = i + 1; j < ids.size(); ++j) pairs.emplace_back(ids[i], ids[j]);
  std::vector<std::string> blocks(pairs.size());
  std::vector<int64_t> counts(pairs.size(), 0);
  parallel_for(0, int64_t(pairs.size()), [&](int64_t k) {
    const auto [i1, i2] = pairs[size_t(k)];
    static const SiftDescriptors kNone;
    const auto d1 = desc.find(i1), d2 = desc.find(i2);
    const auto m = match_sift_descriptors(d1 == desc.end() ? kNone : d1->second, d2 == desc.end() ? kNone : d2->second, o);
    std::ostringstream s;
    s << names.at(i1) << " " << names.at(i2) << "\n";
    for (const auto& [a, b] : m) s << a << " " << b << "\n";
    s << "\n";
    blocks[size_t(k)] = s.str();
    counts[size_t(k)] = int64_t(m.size());
  });
  std::string all;
  int64_t total = 0;
  for (size_t k = 0; k < blocks.size(); ++k) all += blocks[k], total += counts[k];
  write_file_atomic(list_path, all);
  return total;
}

}  // namespace weathergs::capture
