#include "reconstruction/gaussians.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"

namespace weathergs::reconstruction {

template <typename T>
void GaussianSet<T>::resize(size_t n) {
  position.resize(n * 3, T(0));
  log_scale.resize(n * 3, T(0));
  rotation.resize(n * 4, T(0));
  opacity_logit.resize(n, T(0));
  sh.resize(n * kShFloats, T(0));
}

template <typename T>
void GaussianSet<T>::assign_zero(size_t n) {
  position.assign(n * 3, T(0));
  log_scale.assign(n * 3, T(0));
  rotation.assign(n * 4, T(0));
  opacity_logit.assign(n, T(0));
  sh.assign(n * kShFloats, T(0));
}

template <typename T>
void GaussianSet<T>::copy_from(const GaussianSet& o, size_t from, size_t to) {
  std::copy_n(&o.position[from * 3], 3, &position[to * 3]);
  std::copy_n(&o.log_scale[from * 3], 3, &log_scale[to * 3]);
  std::copy_n(&o.rotation[from * 4], 4, &rotation[to * 4]);
  opacity_logit[to] = o.opacity_logit[from];
  std::copy_n(&o.sh[from * kShFloats], kShFloats, &sh[to * kShFloats]);
}

template <typename T>
void GaussianSet<T>::keep(const std::vector<char>& keep_mask) {
  WGS_CHECK_EQ(keep_mask.size(), size());
  size_t out = 0;
  for (size_t i = 0; i < keep_mask.size(); ++i) {
    if (!keep_mask[i]) continue;
    if (out != i) copy_from(*this, i, out);
    ++out;
  }
  resize(out);
}

template struct GaussianSet<float>;
template struct GaussianSet<double>;

const char* to_string(ParamGroup g) {
  switch (g) {
    case ParamGroup::kPosition: return "position";
    case ParamGroup::kShDc: return "sh_dc";
    case ParamGroup::kShRest: return "sh_rest";
    case ParamGroup::kOpacity: return "opacity";
    case ParamGroup::kScale: return "scale";
    case ParamGroup::kRotation: return "rotation";
  }
  return "?";
}

// ---------------------------------------------------------------------------------------------
// PLY

namespace {

std::vector<std::string> ply_property_names() {
  std::vector<std::string> n = {"x", "y", "z", "nx", "ny", "nz", "f_dc_0", "f_dc_1", "f_dc_2"};
  for (int i = 0; i < 45; ++i) n.push_back("f_rest_" + std::to_string(i));
  n.push_back("opacity");
  for (int i = 0; i < 3; ++i) n.push_back("scale_" + std::to_string(i));
  for (int i = 0; i < 4; ++i) n.push_back("rot_" + std::to_string(i));
  return n;
}

int ply_type_size(const std::string& t) {
  if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
  if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
  if (t == "int" || t == "uint" || t == "int32" || t == "uint32" || t == "float" || t == "float32") return 4;
  if (t == "double" || t == "float64") return 8;
  return 0;
}

}  // namespace

void write_ply(const std::string& path, const GaussianSet<float>& g) {
  const size_t n = g.size();
  const std::vector<std::string> names = ply_property_names();
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\nelement vertex " << n << "\n";
  for (const auto& name : names) header << "property float " << name << "\n";
  header << "end_header\n";
  std::string out = header.str();
  const size_t row = names.size();
  std::vector<float> data(n * row);
  for (size_t i = 0; i < n; ++i) {
    float* r = &data[i * row];
    for (int k = 0; k < 3; ++k) r[k] = g.position[i * 3 + k];
    r[3] = r[4] = r[5] = 0.f;  // normals: unused, zero as the reference writes them
    const float* sh = &g.sh[i * kShFloats];
    for (int c = 0; c < 3; ++c) r[6 + c] = sh[c];
    for (int c = 0; c < 3; ++c)
      for (int k = 1; k < kShCoeffs; ++k) r[9 + c * 15 + (k - 1)] = sh[k * 3 + c];
    r[54] = g.opacity_logit[i];
    for (int k = 0; k < 3; ++k) r[55 + k] = g.log_scale[i * 3 + k];
    for (int k = 0; k < 4; ++k) r[58 + k] = g.rotation[i * 4 + k];
  }
  static_assert(sizeof(float) == 4, "PLY float is 32-bit");
  const size_t header_size = out.size();
  out.resize(header_size + data.size() * sizeof(float));
  // The project only targets little-endian machines (x86-64, arm64), so the bytes are copied as is.
  std::memcpy(&out[header_size], data.data(), data.size() * sizeof(float));
  write_file_atomic(path, out);
}

GaussianSet<float> read_ply(const std::string& path) {
  const std::string bytes = read_file(path);
  const std::string end_marker = "end_header\n";
  const size_t end = bytes.find(end_marker);
  if (bytes.compare(0, 4, "ply\n") != 0 || end == std::string::npos)
    throw InputError(path, "not a PLY file (expected 'ply' and 'end_header')");
  std::istringstream header(bytes.substr(0, end));
  std::string line;
  int64_t count = -1;
  bool in_vertex = false, binary_le = false;
  struct Prop { std::string name; int offset, size; std::string type; };
  std::vector<Prop> props;
  int row_size = 0;
  int line_no = 0;
  while (std::getline(header, line)) {
    ++line_no;
    std::istringstream ls(line);
    std::string word;
    ls >> word;
    const std::string where = path + ":" + std::to_string(line_no);
    if (word == "format") {
      std::string fmt;
      ls >> fmt;
      binary_le = fmt == "binary_little_endian";
      if (!binary_le) throw InputError(where, "expected format binary_little_endian, got '" + fmt + "'");
    } else if (word == "element") {
      std::string name;
      int64_t c = -1;
      ls >> name >> c;
      if (name == "vertex") {
        if (c < 0) throw InputError(where, "bad vertex count");
        count = c;
        in_vertex = true;
      } else {
        if (count < 0) throw InputError(where, "expected the vertex element first");
        in_vertex = false;
      }
    } else if (word == "property" && in_vertex) {
      std::string type, name;
      ls >> type >> name;
      if (type == "list") throw InputError(where, "list properties are not supported in the vertex element");
      const int size = ply_type_size(type);
      if (size == 0) throw InputError(where, "unknown property type '" + type + "'");
      props.push_back({name, row_size, size, type});
      row_size += size;
    }
  }
  if (!binary_le) throw InputError(path, "missing 'format binary_little_endian 1.0'");
  if (count < 0) throw InputError(path, "missing 'element vertex'");
  std::map<std::string, const Prop*> by_name;
  for (const auto& p : props) by_name[p.name] = &p;
  auto require = [&](const std::string& name) -> const Prop* {
    auto it = by_name.find(name);
    if (it == by_name.end()) throw InputError(path, "missing vertex property '" + name + "'");
    if (it->second->type != "float" && it->second->type != "float32")
      throw InputError(path, "vertex property '" + name + "' must be float, got " + it->second->type);
    return it->second;
  };
  int num_rest = 0;
  while (by_name.count("f_rest_" + std::to_string(num_rest))) ++num_rest;
  if (num_rest != 0 && num_rest != 9 && num_rest != 24 && num_rest != 45)
    throw InputError(path, "expected 0, 9, 24 or 45 f_rest properties, got " + std::to_string(num_rest));
  const int rest_per_channel = num_rest / 3;
  const size_t data_begin = end + end_marker.size();
  if (bytes.size() - data_begin < size_t(count) * size_t(row_size))
    throw InputError(path, "truncated: expected " + std::to_string(count) + " vertices of " +
                               std::to_string(row_size) + " bytes");
  std::vector<const Prop*> pos = {require("x"), require("y"), require("z")};
  std::vector<const Prop*> dc = {require("f_dc_0"), require("f_dc_1"), require("f_dc_2")};
  std::vector<const Prop*> rest;
  for (int i = 0; i < num_rest; ++i) rest.push_back(require("f_rest_" + std::to_string(i)));
  const Prop* opacity = require("opacity");
  std::vector<const Prop*> scale = {require("scale_0"), require("scale_1"), require("scale_2")};
  std::vector<const Prop*> rot = {require("rot_0"), require("rot_1"), require("rot_2"), require("rot_3")};
  GaussianSet<float> g;
  g.assign_zero(size_t(count));
  const char* base = bytes.data() + data_begin;
  auto get = [&](int64_t i, const Prop* p) {
    float v;
    std::memcpy(&v, base + size_t(i) * row_size + p->offset, 4);
    return v;
  };
  for (int64_t i = 0; i < count; ++i) {
    for (int k = 0; k < 3; ++k) g.position[i * 3 + k] = get(i, pos[k]);
    float* sh = &g.sh[i * kShFloats];
    for (int c = 0; c < 3; ++c) sh[c] = get(i, dc[c]);
    for (int c = 0; c < 3; ++c)
      for (int k = 1; k <= rest_per_channel; ++k) sh[k * 3 + c] = get(i, rest[c * rest_per_channel + k - 1]);
    g.opacity_logit[i] = get(i, opacity);
    for (int k = 0; k < 3; ++k) g.log_scale[i * 3 + k] = get(i, scale[k]);
    for (int k = 0; k < 4; ++k) g.rotation[i * 4 + k] = get(i, rot[k]);
  }
  return g;
}

// ---------------------------------------------------------------------------------------------
// Initialization

namespace {

struct KdTree {
  const std::vector<Eigen::Vector3d>& pts;
  std::vector<int> idx;
  std::vector<int> axis;  // split axis of the node stored at idx[mid]

  explicit KdTree(const std::vector<Eigen::Vector3d>& p) : pts(p), idx(p.size()), axis(p.size(), 0) {
    std::iota(idx.begin(), idx.end(), 0);
    build(0, int(idx.size()));
  }
  void build(int lo, int hi) {
    if (hi - lo <= 1) return;
    Eigen::Vector3d mn = pts[idx[lo]], mx = mn;
    for (int i = lo; i < hi; ++i) { mn = mn.cwiseMin(pts[idx[i]]); mx = mx.cwiseMax(pts[idx[i]]); }
    int ax;
    (mx - mn).maxCoeff(&ax);
    const int mid = (lo + hi) / 2;
    // Ties broken by index so the tree (and the result) does not depend on the sort implementation.
    std::nth_element(idx.begin() + lo, idx.begin() + mid, idx.begin() + hi, [&](int a, int b) {
      return pts[a][ax] < pts[b][ax] || (pts[a][ax] == pts[b][ax] && a < b);
    });
    axis[mid] = ax;
    build(lo, mid);
    build(mid + 1, hi);
  }
  // Keeps the k smallest squared distances in best (sorted ascending).
  void query(int lo, int hi, int self, const Eigen::Vector3d& q, double* best, int k) const {
    if (hi <= lo) return;
    const int mid = (lo + hi) / 2;
    const int p = idx[mid];
    if (p != self) {
      const double d = (pts[p] - q).squaredNorm();
      if (d < best[k - 1]) {
        int j = k - 1;
        while (j > 0 && best[j - 1] > d) { best[j] = best[j - 1]; --j; }
        best[j] = d;
      }
    }
    if (hi - lo == 1) return;
    const int ax = axis[mid];
    const double diff = q[ax] - pts[p][ax];
    const bool left_first = diff <= 0;
    if (left_first) query(lo, mid, self, q, best, k); else query(mid + 1, hi, self, q, best, k);
    if (diff * diff < best[k - 1]) {
      if (left_first) query(mid + 1, hi, self, q, best, k); else query(lo, mid, self, q, best, k);
    }
  }
};

}  // namespace

std::vector<double> mean_sq_dist_3nn(const std::vector<Eigen::Vector3d>& points) {
  std::vector<double> out(points.size(), 0.0);
  if (points.size() < 2) return out;
  KdTree tree(points);
  const int k = int(std::min<size_t>(3, points.size() - 1));
  for (size_t i = 0; i < points.size(); ++i) {
    double best[3] = {INFINITY, INFINITY, INFINITY};
    tree.query(0, int(points.size()), int(i), points[i], best, k);
    double s = 0;
    for (int j = 0; j < k; ++j) s += best[j];
    out[i] = s / k;
  }
  return out;
}

GaussianSet<float> init_from_points(const std::vector<Eigen::Vector3d>& points_world,
                                    const std::vector<Eigen::Vector3d>& colors_rgb01,
                                    const InitOptions& options) {
  WGS_CHECK_EQ(points_world.size(), colors_rgb01.size());
  WGS_CHECK(options.initial_opacity > 0 && options.initial_opacity < 1);
  const size_t n = points_world.size();
  GaussianSet<float> g;
  g.assign_zero(n);
  // A lone point has no neighbours: give it 1 cm, a size visible at any sensible scene scale.
  std::vector<double> d2 = n >= 2 ? mean_sq_dist_3nn(points_world) : std::vector<double>(n, 1e-4);
  const float logit = float(inverse_sigmoid(options.initial_opacity));
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      g.position[i * 3 + k] = float(points_world[i][k]);
      g.log_scale[i * 3 + k] = float(std::log(std::sqrt(std::max(d2[i], options.min_dist2))));
      g.sh[i * kShFloats + k] = float(rgb_to_sh0(std::clamp(colors_rgb01[i][k], 0.0, 1.0)));
    }
    g.rotation[i * 4] = 1.f;
    g.opacity_logit[i] = logit;
  }
  return g;
}

}  // namespace weathergs::reconstruction
