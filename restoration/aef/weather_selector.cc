// The libtorch translation unit of the weather selector (restoration/aef/weather_selector.h).
#include "restoration/aef/weather_selector.h"

#include <torch/torch.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/json_fields.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/rng.h"
#include "restoration/torch_weights.h"

namespace weathergs::restoration::aef {

namespace nn = torch::nn;
namespace F = torch::nn::functional;

namespace {

constexpr uint64_t kStreamSelectorBatch = 0x53454c4241544348ull;  // "SELBATCH": class, example, flip, gain
constexpr int kInputChannels = 1;                                  // the luminance's top-hat

struct SelectorNetImpl : nn::Module {
  nn::Conv2d c1{nullptr}, c2{nullptr}, c3{nullptr}, c4{nullptr};
  nn::Linear fc{nullptr};
  torch::Tensor prototypes;  // [classes, embedding], WeatherClass order

  explicit SelectorNetImpl(const SelectorArchitecture& a) {
    const int k1 = a.channels, k2 = a.channels * 3 / 2, k3 = a.channels * 2;
    c1 = register_module("c1", nn::Conv2d(nn::Conv2dOptions(kInputChannels, k1, 3).padding(1).stride(2)));
    c2 = register_module("c2", nn::Conv2d(nn::Conv2dOptions(k1, k2, 3).padding(1).stride(2)));
    c3 = register_module("c3", nn::Conv2d(nn::Conv2dOptions(k2, k3, 3).padding(1).stride(2)));
    c4 = register_module("c4", nn::Conv2d(nn::Conv2dOptions(k3, k3, 3).padding(1)));
    fc = register_module("fc", nn::Linear(2 * k3, a.embedding));
    prototypes = register_parameter("prototypes", torch::randn({kWeatherClasses, a.embedding}));
  }

  // [B, 4, h, w] -> unit embeddings [B, E].
  torch::Tensor forward(const torch::Tensor& x) {
    torch::Tensor f = torch::relu(c1(x));
    f = torch::relu(c2(f));
    f = torch::relu(c3(f));
    f = torch::relu(c4(f));
    // Mean pooling says how much weather there is, max pooling whether there is any.
    const torch::Tensor pooled = torch::cat({f.mean({2, 3}), f.amax({2, 3})}, 1);
    return F::normalize(fc(pooled), F::NormalizeFuncOptions().dim(1));
  }
  torch::Tensor cosines(const torch::Tensor& e) {
    return torch::matmul(e, F::normalize(prototypes, F::NormalizeFuncOptions().dim(1)).t());
  }
};
TORCH_MODULE(SelectorNet);

int internal_height(const SelectorArchitecture& a, int width, int height) {
  return std::max(16, int(std::lround(double(a.width) * height / width)));
}

// sRGB view -> [1, h, w]: the white top-hat of the luminance, measured at full resolution (particles are
// thin) then area-resampled and amplified. No colour: with RGB the embedder learned the three training
// scenes instead of the weather (held-out accuracy 0.43 per view; docs/restoration.md).
torch::Tensor to_input(const Image& img, const SelectorArchitecture& a, const std::string& where) {
  if (img.empty() || (img.channels != 3 && img.channels != 4))
    throw InputError(where, "expected an RGB image (3 or 4 channels), got " + img.to_string());
  if (img.width < 16 || img.height < 16) throw InputError(where, "image " + img.to_string() + " is too small (16x16 at least)");
  require_finite(img, where);
  const int w = a.width, h = internal_height(a, img.width, img.height);
  cv::Mat m(img.height, img.width, CV_32FC(img.channels), const_cast<float*>(img.data.data()));
  cv::Mat rgb, grey, tophat, small_top;
  if (img.channels == 4) cv::cvtColor(m, rgb, cv::COLOR_RGBA2RGB); else rgb = m;
  cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
  const int r = std::max(1, int(std::lround(a.tophat_radius_px_at_300 * img.width / 300.0)));
  const cv::Mat disk = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1));
  cv::morphologyEx(grey, tophat, cv::MORPH_TOPHAT, disk, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  if (w == img.width && h == img.height) small_top = tophat;
  else cv::resize(tophat, small_top, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  torch::Tensor t = torch::empty({kInputChannels, h, w}, torch::kFloat32);
  constexpr float kTophatGain = 4.f;  // a particle's top-hat (~0.05-0.25) to ~0.2-1
  t[0].copy_(torch::from_blob(small_top.ptr<float>(), {h, w}, torch::kFloat32) * kTophatGain);
  return t.clamp(0.f, 1.f).contiguous();
}

std::string normalized(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  const auto b = s.find_first_not_of(" \t\n"), e = s.find_last_not_of(" \t\n.");
  return b == std::string::npos || e == std::string::npos || e < b ? std::string() : s.substr(b, e - b + 1);
}

}  // namespace

const char* to_string(WeatherClass c) {
  switch (c) {
    case WeatherClass::kSnow: return "snow";
    case WeatherClass::kRain: return "rain";
    case WeatherClass::kNone: return "none";
  }
  return "?";
}

const char* instruction_of(WeatherClass c) {
  switch (c) {
    case WeatherClass::kSnow: return kInstructionDesnow;
    case WeatherClass::kRain: return kInstructionDerain;
    case WeatherClass::kNone: return kInstructionNone;
  }
  return "?";
}

WeatherClass class_of_instruction(const std::string& text) {
  const std::string t = normalized(text);
  for (WeatherClass c : {WeatherClass::kSnow, WeatherClass::kRain, WeatherClass::kNone})
    if (t == normalized(instruction_of(c))) return c;
  const bool snow = t.find("snow") != std::string::npos, rain = t.find("rain") != std::string::npos;
  if (snow != rain) return snow ? WeatherClass::kSnow : WeatherClass::kRain;
  throw InputError("--instruction", "\"" + text + "\" is not an instruction the selector knows (without CLIP only these are: \"" +
                                        kInstructionDesnow + "\", \"" + kInstructionDerain + "\", \"" + kInstructionNone +
                                        "\", or a text naming exactly one of snow / rain)");
}

void SelectorArchitecture::validate() const {
  if (width < 32 || width > 1024) throw InputError("selector architecture width", "expected 32..1024 px, got " + std::to_string(width));
  if (channels < 2 || channels > 128) throw InputError("selector architecture channels", "expected 2..128, got " + std::to_string(channels));
  if (embedding < 2 || embedding > 256)
    throw InputError("selector architecture embedding", "expected 2..256, got " + std::to_string(embedding));
  if (!(tophat_radius_px_at_300 > 0 && tophat_radius_px_at_300 <= 64))
    throw InputError("selector architecture tophat_radius_px_at_300", "expected in (0, 64], got " + std::to_string(tophat_radius_px_at_300));
}

namespace {
constexpr auto kSelectorArchitectureFields = [](auto& s, auto& f) {  // every key required
  f("width", s.width);
  f("channels", s.channels);
  f("embedding", s.embedding);
  f("tophat_radius_px_at_300", s.tophat_radius_px_at_300);
};
}  // namespace

Json SelectorArchitecture::to_json() const { return json_fields::write(*this, kSelectorArchitectureFields); }

SelectorArchitecture SelectorArchitecture::from_json(const JsonReader& r) {
  SelectorArchitecture a = json_fields::read(r, SelectorArchitecture{}, kSelectorArchitectureFields, json_fields::Absent::kError);
  a.validate();
  return a;
}

void SelectorTrainOptions::validate() const {
  arch.validate();
  if (iterations < 1) throw InputError("selector training iterations", "expected at least 1, got " + std::to_string(iterations));
  if (batch < 1 || batch > 512) throw InputError("selector training batch", "expected 1..512, got " + std::to_string(batch));
  if (!(learning_rate > 0 && learning_rate < 1))
    throw InputError("selector training learning_rate", "expected in (0, 1), got " + std::to_string(learning_rate));
  if (!(scale > 0 && scale <= 100)) throw InputError("selector training scale", "expected in (0, 100], got " + std::to_string(scale));
  if (threads < 0) throw InputError("selector training threads", "expected >= 0, got " + std::to_string(threads));
}

struct WeatherSelector::Impl : detail::NetworkState<SelectorArchitecture, SelectorNet> {
  double theta = 0.5;
};

WeatherSelector::~WeatherSelector() = default;
WeatherSelector::WeatherSelector(WeatherSelector&&) noexcept = default;
WeatherSelector& WeatherSelector::operator=(WeatherSelector&&) noexcept = default;

WeatherSelector::WeatherSelector(const SelectorArchitecture& arch, uint64_t seed) : impl_(std::make_unique<Impl>()) {
  arch.validate();
  impl_->arch = arch;
  torch::manual_seed(seed);
  impl_->net = SelectorNet(arch);
  impl_->net->eval();
}

const SelectorArchitecture& WeatherSelector::architecture() const { return impl_->arch; }
double WeatherSelector::theta() const { return impl_->theta; }
void WeatherSelector::set_theta(double t) {
  if (!(t >= -1 && t <= 1)) throw InputError("selector theta", "expected in [-1, 1], got " + std::to_string(t));
  impl_->theta = t;
}
const Json& WeatherSelector::metadata() const { return impl_->metadata; }

int64_t WeatherSelector::parameter_count() const {
  return detail::parameter_count(*impl_->net);
}

void WeatherSelector::save(const std::string& stem, const Json& extra) const {
  detail::save_network(
      *impl_, stem, extra, kSelectorFormat, kSelectorFormatVersion,
      {{"theta", impl_->theta},
       {"prototypes", {to_string(WeatherClass::kSnow), to_string(WeatherClass::kRain), to_string(WeatherClass::kNone)}},
       {"instructions", {kInstructionDesnow, kInstructionDerain, kInstructionNone}}});
}

WeatherSelector WeatherSelector::load(const std::string& stem) {
  const JsonReader r = detail::open_weights(stem, kSelectorFormat, kSelectorFormatVersion, "weather selector");
  WeatherSelector s(SelectorArchitecture::from_json(r.child("architecture")), 0);
  detail::load_weights(*s.impl_->net, r, stem);
  s.impl_->theta = r.get_number("theta", -1, 1);
  s.impl_->metadata = r.value();
  return s;
}

SelectorTrainRecord WeatherSelector::train(const std::vector<SelectorExample>& examples, const SelectorTrainOptions& o) {
  o.validate();
  if (examples.empty()) throw InputError("selector training set", "is empty");
  const auto start = std::chrono::steady_clock::now();
  torch::set_num_threads(o.threads > 0 ? o.threads : num_threads());
  std::array<std::vector<torch::Tensor>, kWeatherClasses> by_class;
  for (size_t i = 0; i < examples.size(); ++i) {
    const torch::Tensor x = to_input(examples[i].image, impl_->arch, "selector training example " + std::to_string(i));
    if (!by_class[0].empty() || !by_class[1].empty() || !by_class[2].empty()) {
      const torch::Tensor& any = !by_class[0].empty() ? by_class[0][0] : !by_class[1].empty() ? by_class[1][0] : by_class[2][0];
      if (x.sizes() != any.sizes())
        throw InputError("selector training example " + std::to_string(i), "has another aspect ratio than the first example");
    }
    by_class[size_t(examples[i].label)].push_back(x);
  }
  std::vector<int> present;
  for (int c = 0; c < kWeatherClasses; ++c)
    if (!by_class[size_t(c)].empty()) present.push_back(c);
  SelectorNet& net = impl_->net;
  net->train();
  torch::optim::Adam adam(net->parameters(), torch::optim::AdamOptions(o.learning_rate));
  SelectorTrainRecord rec;
  rec.parameters = parameter_count();
  ProgressBar bar("train selector", o.iterations);
  double window = 0;
  for (int it = 0; it < o.iterations; ++it) {
    // Class-balanced batches (a class first, then one of its views), flips and a brightness gain,
    // keyed on (seed, iteration).
    Rng rng(o.seed, kStreamSelectorBatch, uint64_t(it));
    std::vector<torch::Tensor> bx;
    std::vector<int64_t> labels;
    for (int b = 0; b < o.batch; ++b) {
      const int c = present[rng.uniform_int(uint32_t(present.size()))];
      const auto& pool = by_class[size_t(c)];
      torch::Tensor x = pool[rng.uniform_int(uint32_t(pool.size()))];
      if (rng.uniform() < 0.5f) x = x.flip({2});
      const float gain = rng.uniform(0.75f, 1.25f);
      bx.push_back((x * gain).clamp(0.f, 1.f));
      labels.push_back(c);
    }
    detail::set_cosine_learning_rate(adam, o.learning_rate, it, o.iterations);
    adam.zero_grad();
    const torch::Tensor logits = o.scale * net->cosines(net->forward(torch::stack(bx)));
    const torch::Tensor loss = F::cross_entropy(logits, torch::tensor(labels, torch::kInt64));
    loss.backward();
    adam.step();
    const double l = loss.item<double>();
    if (!std::isfinite(l)) throw NumericalDivergence("selector training loss became non-finite at iteration " + std::to_string(it));
    window += l;
    if ((it + 1) % 50 == 0 || it + 1 == o.iterations) {
      rec.loss_curve.push_back(window / ((it % 50) + 1));
      window = 0;
    }
    if (o.progress) bar.tick();
  }
  net->eval();
  rec.seconds = seconds_since(start);
  return rec;
}

std::vector<float> WeatherSelector::embed(const Image& image, const std::string& where) const {
  const torch::Tensor x = to_input(image, impl_->arch, where).unsqueeze(0);
  torch::set_num_threads(1);  // ~1 MFLOP: threading costs more than it gives
  torch::NoGradGuard no_grad;
  const torch::Tensor e = impl_->net->forward(x)[0].contiguous();
  return std::vector<float>(e.data_ptr<float>(), e.data_ptr<float>() + e.numel());
}

Selection WeatherSelector::select(const std::vector<float>& embedding) const { return select(embedding, impl_->theta); }

Selection WeatherSelector::select(const std::vector<float>& embedding, double theta) const {
  if (int(embedding.size()) != impl_->arch.embedding)
    throw InputError("selector embedding", "has " + std::to_string(embedding.size()) + " values, expected " +
                                               std::to_string(impl_->arch.embedding));
  torch::NoGradGuard no_grad;
  const torch::Tensor e = torch::tensor(embedding, torch::kFloat32).unsqueeze(0);
  const torch::Tensor c = impl_->net->cosines(e)[0].contiguous();
  Selection s;
  for (int k = 0; k < kWeatherClasses; ++k) s.cosine[size_t(k)] = c[k].item<double>();
  const double snow = s.cosine[size_t(WeatherClass::kSnow)], rain = s.cosine[size_t(WeatherClass::kRain)];
  const double none = s.cosine[size_t(WeatherClass::kNone)];
  const WeatherClass best = snow >= rain ? WeatherClass::kSnow : WeatherClass::kRain;
  const double cos_best = std::max(snow, rain);
  s.choice = cos_best >= theta && cos_best > none ? best : WeatherClass::kNone;
  return s;
}

std::vector<float> WeatherSelector::mean_embedding(const std::vector<std::vector<float>>& embeddings) {
  if (embeddings.empty()) throw InputError("selector", "no embeddings to average");
  std::vector<double> sum(embeddings[0].size(), 0.0);
  for (const auto& e : embeddings) {
    WGS_CHECK_EQ(e.size(), sum.size());
    for (size_t i = 0; i < e.size(); ++i) sum[i] += e[i];
  }
  double n2 = 0;
  for (double v : sum) n2 += v * v;
  const double inv = n2 > 0 ? 1 / std::sqrt(n2) : 0;
  std::vector<float> out(sum.size());
  for (size_t i = 0; i < sum.size(); ++i) out[i] = float(sum[i] * inv);
  return out;
}

}  // namespace weathergs::restoration::aef
