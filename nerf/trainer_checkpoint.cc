// Radiance-field trainer checkpoints (split from trainer.cc): everything a restored trainer needs to
// step on to the same bits. The gradient buffers and the touched flags are not stored: every step
// leaves them zero.
#include <cstring>
#include <fstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "nerf/trainer.h"

namespace weathergs::nerf {

// "WGSNCKP1", a JSON header line, then float32 arrays in a fixed order: the lattice's values, Adam's
// first and second moments (kSaved per point: the density and the colour coefficients, the floats the
// optimizer updates; the padding stays zero), the environment and its two moments.
namespace {

constexpr const char* kCheckpointMagic = "WGSNCKP1";
constexpr int kSaved = 1 + 3 * kShCoeffs;
constexpr int64_t kPointsPerBlock = 1 << 16;  // buffered per write, so a checkpoint never doubles the memory

void write_points(std::ofstream& f, const std::vector<float>& a, int64_t points) {
  std::vector<float> buf;
  for (int64_t lo = 0; lo < points; lo += kPointsPerBlock) {
    const int64_t hi = std::min(points, lo + kPointsPerBlock);
    buf.resize(size_t(hi - lo) * kSaved);
    for (int64_t p = lo; p < hi; ++p)
      std::memcpy(&buf[size_t(p - lo) * kSaved], &a[size_t(p) * kStride], sizeof(float) * kSaved);
    f.write(reinterpret_cast<const char*>(buf.data()), std::streamsize(buf.size() * sizeof(float)));
  }
}

void read_points(std::ifstream& f, std::vector<float>& a, int64_t points) {
  a.assign(size_t(points) * kStride, 0.f);
  std::vector<float> buf;
  for (int64_t lo = 0; lo < points && f; lo += kPointsPerBlock) {
    const int64_t hi = std::min(points, lo + kPointsPerBlock);
    buf.resize(size_t(hi - lo) * kSaved);
    f.read(reinterpret_cast<char*>(buf.data()), std::streamsize(buf.size() * sizeof(float)));
    for (int64_t p = lo; p < hi; ++p)
      std::memcpy(&a[size_t(p) * kStride], &buf[size_t(p - lo) * kSaved], sizeof(float) * kSaved);
  }
}

}  // namespace

void NerfTrainer::save_checkpoint(const std::string& path, const Json& run_state) const {
  const GridDims d = field_.dims();
  const Json header{{"iteration", iteration_},
                    {"level", level_},
                    {"adam_steps", adam_steps_},
                    {"dims", {d.nu, d.nv, d.nw}},
                    {"env_floats", field_.env().size()},
                    {"frame", field_.frame().to_json()},
                    {"options", options_.to_json()},
                    {"run_state", run_state}};
  write_file_atomic_with(path, [&](const std::string& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    f << kCheckpointMagic << '\n' << header.dump() << '\n';
    for (const std::vector<float>* a : {&field_.params(), &m_, &v_}) write_points(f, *a, d.points());
    for (const std::vector<float>* a : {&field_.env(), &env_m_, &env_v_})
      f.write(reinterpret_cast<const char*>(a->data()), std::streamsize(a->size() * sizeof(float)));
    if (!f) throw InputError(path, "could not write the checkpoint");
  });
}

Json NerfTrainer::load_checkpoint(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw InputError(path, "missing or unreadable: not a radiance-field checkpoint");
  std::string magic, line;
  std::getline(f, magic);
  if (magic != kCheckpointMagic) throw InputError(path, "not a weathergs radiance-field checkpoint (bad magic)");
  std::getline(f, line);
  Json hj;
  try {
    hj = Json::parse(line);
  } catch (const std::exception& e) {
    throw InputError(path, std::string("corrupt checkpoint header: ") + e.what());
  }
  JsonReader h(hj, path);
  if (const std::string why = settings_mismatch(h.child("options").value(), options_.to_json()); !why.empty())
    throw InputError(h.where("options"), "the checkpoint was written with other options (" + why +
                                             "): resume with its options, or start over with --force");
  if (const std::string why = settings_mismatch(h.child("frame").value(), field_.frame().to_json()); !why.empty())
    throw InputError(h.where("frame"), "the checkpoint's frustum frame differs (" + why + "): the cameras or SfM points changed");
  const int iteration = h.get<int>("iteration");
  const int level = h.get<int>("level");
  const int adam_steps = h.get<int>("adam_steps");
  if (iteration < 0 || iteration > options_.iterations)
    throw InputError(h.where("iteration"), "must be in [0, " + std::to_string(options_.iterations) + "]");
  if (level < 0 || level >= int(options_.level_scales.size()))
    throw InputError(h.where("level"), "must be in [0, " + std::to_string(options_.level_scales.size()) + ")");
  const auto dims = h.get_array<3>("dims", 2, 1 << 20);
  const GridDims d{int(dims[0]), int(dims[1]), int(dims[2])};
  const GridDims want = level_dims(level);
  if (!(d == want))
    throw InputError(h.where("dims"), "level " + std::to_string(level) + " of these options has " + std::to_string(want.nu) +
                                          " x " + std::to_string(want.nv) + " x " + std::to_string(want.nw) + " lattice points");
  if (h.get<size_t>("env_floats") != field_.env().size()) throw InputError(h.where("env_floats"), "unexpected size");
  Json run_state = h.child("run_state").value();
  h.finish();

  // The lattice of that level as start_level makes it (same frame and density shift), then its values.
  RadianceField field(field_.frame(), d, options_.alpha_init);
  read_points(f, field.params(), d.points());
  read_points(f, m_, d.points());
  read_points(f, v_, d.points());
  for (std::vector<float>* a : {&field.env(), &env_m_, &env_v_}) {
    a->assign(field_.env().size(), 0.f);
    f.read(reinterpret_cast<char*>(a->data()), std::streamsize(a->size() * sizeof(float)));
  }
  if (!f || f.peek() != std::char_traits<char>::eof())
    throw InputError(path, "truncated or oversized: expected " + std::to_string(3 * (d.points() * kSaved + int64_t(field_.env().size()))) +
                               " float32 values after the header");
  for (float x : field.params())
    if (!std::isfinite(x)) throw InputError(path, "holds non-finite values");
  field.rebuild_occupancy();
  field_ = std::move(field);
  grad_.assign(m_.size(), 0.f);
  touched_.assign(size_t(d.points()), 0);
  env_grad_.assign(env_m_.size(), 0.f);
  iteration_ = iteration, level_ = level, adam_steps_ = adam_steps;
  return run_state;
}

}  // namespace weathergs::nerf
