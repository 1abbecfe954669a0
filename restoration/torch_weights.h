// Internal to restoration/: the scaffold the learned networks share (the LED, the AEF plugins and the
// weather selector): their residual block, the state behind their torch-free classes, the weights
// file pair (`<stem>.json` manifest + `<stem>.bin` float32 blob) and two training helpers. Includes libtorch, so
// only the libtorch translation units (lens_detector.cc, aef_plugin.cc, weather_selector.cc) include it.
#pragma once

#include <torch/torch.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_reader.h"
#include "core/sha256.h"

namespace weathergs::restoration::detail {

inline std::string shape_string(const std::vector<int64_t>& s) {
  std::string out = "[";
  for (size_t i = 0; i < s.size(); ++i) out += (i ? ", " : "") + std::to_string(s[i]);
  return out + "]";
}

inline int64_t parameter_count(const torch::nn::Module& module) {
  int64_t n = 0;
  for (const auto& p : module.parameters()) n += p.numel();
  return n;
}

// The learning rate of iteration `it` of `iterations`: a cosine from `base` down to 5% of it.
inline void set_cosine_learning_rate(torch::optim::Adam& adam, double base, int it, int iterations) {
  const double lr = base * (0.05 + 0.95 * 0.5 * (1 + std::cos(M_PI * it / iterations)));
  for (auto& g : adam.param_groups()) static_cast<torch::optim::AdamOptions&>(g.options()).lr(lr);
}

inline const char* kWeightsFix = "; retrain with `make models` or restore the file from the repository (models/README.md)";

// Writes `<stem>.bin` (parameters in named_parameters order) and `<stem>.json` (`manifest` plus the
// tensor table and the blob's sha256), each atomically.
inline void save_weights(const torch::nn::Module& module, const std::string& stem, Json manifest) {
  std::string blob;
  Json table = Json::array();
  for (const auto& p : module.named_parameters()) {
    const torch::Tensor t = p.value().detach().contiguous().to(torch::kFloat32);
    table.push_back({{"name", p.key()}, {"shape", t.sizes().vec()}});
    blob.append(reinterpret_cast<const char*>(t.data_ptr<float>()), size_t(t.numel()) * sizeof(float));
  }
  manifest["tensors"] = table;
  manifest["weights_file"] = std::filesystem::path(stem + ".bin").filename().string();
  manifest["weights_sha256"] = sha256_hex(blob);
  write_file_atomic(stem + ".bin", blob);
  write_file_atomic(stem + ".json", manifest.dump(2) + "\n");
}

// Opens `<stem>.json` and checks its format and version; InputError naming the file and the fix.
inline JsonReader open_weights(const std::string& stem, const std::string& format, int version, const std::string& what) {
  const std::string json_path = stem + ".json";
  if (!std::filesystem::exists(json_path)) throw InputError(json_path, "missing: no " + what + " weights manifest" + kWeightsFix);
  JsonReader r = JsonReader::from_file(json_path);
  const std::string f = r.get_or<std::string>("format", "");
  if (f != format)
    throw InputError(r.where("format"), "expected \"" + format + "\" (" + what + " weights), got \"" + f + "\"" + kWeightsFix);
  const int v = r.get<int>("version");
  if (v != version)
    throw InputError(r.where("version"), "expected " + what + " weights version " + std::to_string(version) + ", got " +
                                             std::to_string(v) + kWeightsFix);
  return r;
}

// Reads `<stem>.bin` into the module's parameters after checking the sha256 and the tensor table.
inline void load_weights(torch::nn::Module& module, const JsonReader& r, const std::string& stem) {
  const std::string bin_path = stem + ".bin";
  if (!std::filesystem::exists(bin_path)) throw InputError(bin_path, std::string("missing: the weights blob") + kWeightsFix);
  std::ifstream in(bin_path, std::ios::binary);
  const std::string blob((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (sha256_hex(blob) != r.get<std::string>("weights_sha256"))
    throw InputError(bin_path, "corrupt: its sha256 differs from " + stem + ".json" + kWeightsFix);
  const auto params = module.named_parameters();
  const JsonReader table = r.child("tensors");
  if (table.size() != params.size())
    throw InputError(table.where(), "expected " + std::to_string(params.size()) + " tensors for this architecture, got " +
                                        std::to_string(table.size()) + kWeightsFix);
  size_t offset = 0;
  torch::NoGradGuard no_grad;
  for (size_t i = 0; i < params.size(); ++i) {
    const JsonReader e = table.at(i);
    const auto& p = params[i];
    const std::string name = e.get<std::string>("name");
    const std::vector<int64_t> shape = e.get<std::vector<int64_t>>("shape");
    if (name != p.key() || shape != p.value().sizes().vec())
      throw InputError(e.where(), "expected tensor \"" + p.key() + "\" of shape " + shape_string(p.value().sizes().vec()) +
                                      " (this build's architecture), got \"" + name + "\" of shape " + shape_string(shape) +
                                      ": the weights are for another version of the network" + kWeightsFix);
    const size_t bytes = size_t(p.value().numel()) * sizeof(float);
    if (offset + bytes > blob.size()) throw InputError(bin_path, std::string("truncated: shorter than its tensor table") + kWeightsFix);
    std::memcpy(p.value().data_ptr<float>(), blob.data() + offset, bytes);
    offset += bytes;
  }
  if (offset != blob.size()) throw InputError(bin_path, std::string("longer than its tensor table") + kWeightsFix);
}

// Two dilated 3x3 convolutions with a skip: the body of the LED and of the AEF plugins.
struct ResidualBlockImpl : torch::nn::Module {
  torch::nn::Conv2d c1{nullptr}, c2{nullptr};
  ResidualBlockImpl(int ch, int dilation) {
    using torch::nn::Conv2d, torch::nn::Conv2dOptions;
    c1 = register_module("c1", Conv2d(Conv2dOptions(ch, ch, 3).padding(dilation).dilation(dilation)));
    c2 = register_module("c2", Conv2d(Conv2dOptions(ch, ch, 3).padding(dilation).dilation(dilation)));
  }
  torch::Tensor forward(const torch::Tensor& x) { return torch::relu(x + c2(torch::relu(c1(x)))); }
};
TORCH_MODULE(ResidualBlock);

// What every learned network keeps behind its torch-free class: its architecture, its module and the
// manifest it was loaded with. A network's own settings (a threshold, a plugin kind) sit beside it.
template <typename Arch, typename Net>
struct NetworkState {
  Arch arch;
  Net net{nullptr};
  Json metadata = Json::object();
};

// The one save envelope: `extra` (when an object) with the format, version, architecture and
// parameter count, then the network's own `fields` (a null field removes that key), then the weights.
template <typename Arch, typename Net>
void save_network(const NetworkState<Arch, Net>& s, const std::string& stem, const Json& extra, const char* format,
                  int version, const Json& fields) {
  Json j = extra.is_object() ? extra : Json::object();
  j["format"] = format;
  j["version"] = version;
  j["architecture"] = s.arch.to_json();
  for (const auto& [key, value] : fields.items()) {
    if (value.is_null()) j.erase(key);
    else j[key] = value;
  }
  j["parameters"] = parameter_count(*s.net);
  save_weights(*s.net, stem, j);  // + the tensor table, the blob and its sha256
}

}  // namespace weathergs::restoration::detail
