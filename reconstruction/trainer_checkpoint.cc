// Trainer checkpoints (split from trainer.cc): save and restore everything a resumed run needs to
// end byte-identical to an uninterrupted one.
#include <cstring>

#include "core/atomic_file.h"
#include "core/error.h"
#include "reconstruction/distractors.h"
#include "reconstruction/trainer.h"

namespace weathergs::reconstruction {

// ---------------------------------------------------------------------------------------------
// Checkpoints: "WGSCKPT3", uint64 JSON length, JSON header, then the float arrays in a fixed order,
// the int32 view counts, the int32 owners (distractors.h), the robust mask's histogram (doubles;
// robust runs only) and the in-the-wild state ("wild_floats" floats; gs-w-lite only). Format 2 had no
// owners (read as all scene); format 1 had no robust state.

namespace {
constexpr char kCheckpointMagic[8] = {'W', 'G', 'S', 'C', 'K', 'P', 'T', '3'};
constexpr char kCheckpointMagicV2[8] = {'W', 'G', 'S', 'C', 'K', 'P', 'T', '2'};
constexpr char kCheckpointMagicV1[8] = {'W', 'G', 'S', 'C', 'K', 'P', 'T', '1'};
}

void Trainer::save_checkpoint(const std::string& path, double train_seconds,
                              std::optional<double> train_cpu_seconds) const {
  Json header{{"iteration", iteration_},
              {"sh_degree", sh_degree_},
              {"num_gaussians", g_.size()},
              {"adam_steps", std::vector<int64_t>(adam_steps_.begin(), adam_steps_.end())},
              {"extent", extent_},
              {"train_seconds", train_seconds},
              {"robust_threshold", robust_mask_.threshold()},
              {"robust_bins", options_.robust == TrainOptions::Robust::kNone ? 0 : robust_mask_.options().bins},
              {"wild_floats", wild_.state_size()},
              {"options", options_.to_json()}};
  if (train_cpu_seconds) header["train_cpu_seconds"] = *train_cpu_seconds;
  const std::string h = header.dump();
  std::string out(kCheckpointMagic, 8);
  const uint64_t len = h.size();
  out.append(reinterpret_cast<const char*>(&len), 8);
  out += h;
  auto put = [&](const std::vector<float>& a) {
    out.append(reinterpret_cast<const char*>(a.data()), a.size() * sizeof(float));
  };
  for (const GaussianSet<float>* s : {&g_, &adam_m_, &adam_v_}) {
    put(s->position); put(s->log_scale); put(s->rotation); put(s->opacity_logit); put(s->sh);
  }
  put(grad_accum_);
  put(max_radii_);
  out.append(reinterpret_cast<const char*>(grad_count_.data()), grad_count_.size() * sizeof(int32_t));
  out.append(reinterpret_cast<const char*>(owner_.data()), owner_.size() * sizeof(int32_t));
  if (options_.robust != TrainOptions::Robust::kNone) {
    const std::vector<double>& h = robust_mask_.histogram();
    out.append(reinterpret_cast<const char*>(h.data()), h.size() * sizeof(double));
  }
  put(wild_.state());  // gs-w-lite: appearance, visibility and their Adam moments (empty otherwise)
  write_file_atomic(path, out);
}

double Trainer::load_checkpoint(const std::string& path, std::optional<double>* train_cpu_seconds) {
  const std::string bytes = read_file(path);
  if (bytes.size() >= 8 && std::memcmp(bytes.data(), kCheckpointMagicV1, 8) == 0)
    throw InputError(path, "checkpoint of an older weathergs (format 1); start the run over with --force");
  const bool v2 = bytes.size() >= 8 && std::memcmp(bytes.data(), kCheckpointMagicV2, 8) == 0;
  if (bytes.size() < 16 || (!v2 && std::memcmp(bytes.data(), kCheckpointMagic, 8) != 0))
    throw InputError(path, "not a weathergs training checkpoint (bad magic)");
  uint64_t len;
  std::memcpy(&len, bytes.data() + 8, 8);
  if (len > bytes.size() - 16) throw InputError(path, "truncated checkpoint header");
  Json hj;
  try {
    hj = Json::parse(bytes.substr(16, len));
  } catch (const std::exception& e) {
    throw InputError(path, std::string("corrupt checkpoint header: ") + e.what());
  }
  JsonReader h(hj, path);
  const TrainOptions stored = TrainOptions::from_json(h.child("options"));
  if (stored.to_json() != options_.to_json()) {
    // Name every differing option and both values, so the user can pass the stored ones back.
    const Json a = stored.to_json(), b = options_.to_json();
    std::string diff;
    for (auto it = a.begin(); it != a.end(); ++it) {
      const auto jt = b.find(it.key());
      if (jt != b.end() && *jt == it.value()) continue;
      diff += (diff.empty() ? "" : ", ") + it.key() + ": checkpoint " + it.value().dump() + ", now " +
              (jt == b.end() ? std::string("absent") : jt->dump());
    }
    throw InputError(path, "checkpoint was written with different training options (" + diff +
                               "): resume with the checkpoint's values, or start over with --force");
  }
  const int iteration = h.get<int>("iteration");
  const int sh_degree = h.get<int>("sh_degree");
  const size_t n = h.get<size_t>("num_gaussians");
  JsonReader steps = h.child("adam_steps");
  if (steps.size() != 6) throw InputError(steps.where(), "expected 6 step counts");
  std::array<int64_t, 6> adam_steps{};
  for (int k = 0; k < 6; ++k) adam_steps[k] = steps.at(k).as<int64_t>();
  const double extent = h.get<double>("extent");
  const double seconds = h.get<double>("train_seconds");
  const double robust_threshold = h.get<double>("robust_threshold");
  const size_t robust_bins = h.get<size_t>("robust_bins");
  const size_t wild_floats = h.get_or<size_t>("wild_floats", 0);
  std::optional<double> cpu;  // absent from checkpoints of builds that did not count CPU seconds
  if (h.has("train_cpu_seconds")) cpu = h.get<double>("train_cpu_seconds");
  h.finish();
  if (wild_floats != wild_.state_size())
    throw InputError(path, "checkpoint in-the-wild state of " + std::to_string(wild_floats) + " values, expected " +
                               std::to_string(wild_.state_size()));
  const size_t want_bins = options_.robust == TrainOptions::Robust::kNone ? 0 : size_t(robust_mask_.options().bins);
  if (robust_bins != want_bins)
    throw InputError(path, "checkpoint robust_bins = " + std::to_string(robust_bins) + ", expected " +
                               std::to_string(want_bins));
  const size_t floats_per = 3 + 3 + 4 + 1 + kShFloats;
  const size_t int_arrays = v2 ? 1 : 2;  // view counts (+ owners)
  const size_t expected = 16 + len + n * (3 * floats_per + 2) * sizeof(float) + int_arrays * n * sizeof(int32_t) +
                        robust_bins * sizeof(double) + wild_floats * sizeof(float);
  if (bytes.size() != expected)
    throw InputError(path, "checkpoint size " + std::to_string(bytes.size()) + " bytes, expected " +
                               std::to_string(expected));
  size_t off = 16 + len;
  auto get = [&](std::vector<float>& a, size_t count) {
    a.resize(count);
    std::memcpy(a.data(), bytes.data() + off, count * sizeof(float));
    off += count * sizeof(float);
  };
  for (GaussianSet<float>* s : {&g_, &adam_m_, &adam_v_}) {
    get(s->position, n * 3); get(s->log_scale, n * 3); get(s->rotation, n * 4); get(s->opacity_logit, n);
    get(s->sh, n * kShFloats);
  }
  get(grad_accum_, n);
  get(max_radii_, n);
  grad_count_.resize(n);
  std::memcpy(grad_count_.data(), bytes.data() + off, n * sizeof(int32_t));
  off += n * sizeof(int32_t);
  std::vector<int32_t> owner(n, kSceneOwner);
  if (!v2) {
    std::memcpy(owner.data(), bytes.data() + off, n * sizeof(int32_t));
    off += n * sizeof(int32_t);
  }
  int64_t distractors = 0;
  for (const int32_t o : owner) {
    if (o != kSceneOwner && (o < 0 || size_t(o) >= views_.size()))
      throw InputError(path, "checkpoint owner " + std::to_string(o) + " is not a training view (0.." +
                                 std::to_string(views_.size() - 1) + ")");
    distractors += o != kSceneOwner;
  }
  if (robust_bins > 0) {
    std::vector<double> hist(robust_bins);
    std::memcpy(hist.data(), bytes.data() + off, robust_bins * sizeof(double));
    robust_mask_.restore(std::move(hist), robust_threshold);
    off += robust_bins * sizeof(double);
  }
  if (wild_floats > 0) {
    std::vector<float> w;
    get(w, wild_floats);
    wild_.restore(w);
  }
  owner_ = std::move(owner);
  num_distractors_ = distractors;
  iteration_ = iteration;
  sh_degree_ = sh_degree;
  adam_steps_ = adam_steps;
  extent_ = extent;
  parameters_checked_ = false;  // the loaded parameters are scanned before the next step uses them
  if (train_cpu_seconds) *train_cpu_seconds = cpu;
  return seconds;
}

}  // namespace weathergs::reconstruction
