// One of the two libtorch translation units of the learned AEF (the other is weather_selector.cc).
#include "restoration/aef/aef_plugin.h"

#include <torch/torch.h>

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

constexpr uint64_t kStreamAefBatch = 0x4145464241544348ull;  // "AEFBATCH": examples, crops, flips
constexpr int kInputChannels = 7;                             // RGB, opening(RGB), top-hat(luminance)

using detail::ResidualBlock;

torch::Tensor upsample_to(const torch::Tensor& x, const torch::Tensor& like) {
  return F::interpolate(x, F::InterpolateFuncOptions()
                               .size(std::vector<int64_t>{like.size(2), like.size(3)})
                               .mode(torch::kBilinear)
                               .align_corners(false));
}

// The encoder-decoder: [B, 7, H, W] -> [B, 4, H, W] = (alpha logit correction, delta RGB), full resolution.
struct AefNetImpl : nn::Module {
  nn::Conv2d e0{nullptr}, e1{nullptr}, e2{nullptr}, d1{nullptr}, d0{nullptr}, head{nullptr};
  nn::ModuleList blocks;

  explicit AefNetImpl(const AefArchitecture& a) {
    const int c0 = a.channels, c1 = 2 * a.channels, c2 = a.bottleneck;
    e0 = register_module("e0", nn::Conv2d(nn::Conv2dOptions(kInputChannels, c0, 3).padding(1)));
    e1 = register_module("e1", nn::Conv2d(nn::Conv2dOptions(c0, c1, 3).padding(1).stride(2)));
    e2 = register_module("e2", nn::Conv2d(nn::Conv2dOptions(c1, c2, 3).padding(1).stride(2)));
    blocks = register_module("blocks", nn::ModuleList());
    for (int b = 0; b < a.residual_blocks; ++b) blocks->push_back(ResidualBlock(c2, 1 << b));
    d1 = register_module("d1", nn::Conv2d(nn::Conv2dOptions(c2 + c1, c1, 3).padding(1)));
    d0 = register_module("d0", nn::Conv2d(nn::Conv2dOptions(c1 + c0, c0, 3).padding(1)));
    head = register_module("head", nn::Conv2d(nn::Conv2dOptions(c0, 4, 1)));
    // The corrections start near 0: the untrained network is the classical top-hat (composite()).
    torch::NoGradGuard no_grad;
    head->bias.zero_();
    head->weight.mul_(0.1);
  }

  torch::Tensor forward(const torch::Tensor& x) {
    const torch::Tensor f0 = torch::relu(e0(x));
    const torch::Tensor f1 = torch::relu(e1(f0));
    torch::Tensor f = torch::relu(e2(f1));
    for (const auto& b : *blocks) f = b->as<ResidualBlock>()->forward(f);
    torch::Tensor u = torch::relu(d1(torch::cat({upsample_to(f, f1), f1}, 1)));
    u = torch::relu(d0(torch::cat({upsample_to(u, f0), f0}, 1)));
    return head(u);
  }
};
TORCH_MODULE(AefNet);

// The alpha logit: the classical top-hat's decision as a prior, gain * (top-hat - threshold), plus the
// network's correction (which learns what the top-hat gets wrong: scene details on clear views, faint
// or wide particles).
torch::Tensor alpha_logit(const torch::Tensor& x, const torch::Tensor& out, const AefArchitecture& a) {
  return a.prior_gain * (x.slice(1, 6, 7) - a.prior_threshold) + out.slice(1, 0, 1);
}

// restored = I + alpha (B - I), B = opening + delta: the compositing at full resolution.
torch::Tensor composite(const torch::Tensor& x, const torch::Tensor& out, const AefArchitecture& arch) {
  const torch::Tensor image = x.slice(1, 0, 3), opened = x.slice(1, 3, 6);
  const torch::Tensor a = torch::sigmoid(alpha_logit(x, out, arch));
  return image + a * (opened + out.slice(1, 1, 4) - image);
}

// SSIM with a 7x7 Gaussian window (sigma 1.5), valid region only (no padded borders in the mean).
torch::Tensor ssim(const torch::Tensor& a, const torch::Tensor& b) {
  const int k = 7;
  torch::Tensor g = torch::arange(k, torch::kFloat32) - (k - 1) / 2.0;
  g = torch::exp(-(g * g) / (2 * 1.5 * 1.5));
  g = g / g.sum();
  const torch::Tensor w = (g.unsqueeze(1) * g.unsqueeze(0)).expand({3, 1, k, k}).contiguous();
  auto blur = [&](const torch::Tensor& t) { return F::conv2d(t, w, F::Conv2dFuncOptions().groups(3)); };
  const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
  const torch::Tensor ma = blur(a), mb = blur(b);
  const torch::Tensor saa = blur(a * a) - ma * ma, sbb = blur(b * b) - mb * mb, sab = blur(a * b) - ma * mb;
  return ((2 * ma * mb + c1) * (2 * sab + c2) / ((ma * ma + mb * mb + c1) * (saa + sbb + c2))).mean();
}

torch::Tensor aef_loss(const torch::Tensor& x, const torch::Tensor& out, const torch::Tensor& target,
                       const torch::Tensor& alpha, const AefTrainOptions& o) {
  const torch::Tensor restored = composite(x, out, o.arch);
  const torch::Tensor l1 = (restored - target).abs().mean();
  const torch::Tensor dssim = 1 - ssim(restored, target);
  const torch::Tensor bce = F::binary_cross_entropy_with_logits(alpha_logit(x, out, o.arch), alpha);
  return (1 - o.ssim_weight) * l1 + o.ssim_weight * dssim + o.alpha_weight * bce;
}

cv::Mat rgb_mat(const Image& img, const std::string& where) {
  if (img.empty() || (img.channels != 3 && img.channels != 4))
    throw InputError(where, "expected an RGB image (3 or 4 channels), got " + img.to_string());
  if (img.width < 8 || img.height < 8) throw InputError(where, "image " + img.to_string() + " is too small (8x8 at least)");
  require_finite(img, where);
  cv::Mat m(img.height, img.width, CV_32FC(img.channels), const_cast<float*>(img.data.data()));
  cv::Mat rgb;
  if (img.channels == 4) cv::cvtColor(m, rgb, cv::COLOR_RGBA2RGB); else rgb = m.clone();
  return rgb;
}

torch::Tensor hwc_to_chw(const cv::Mat& m) {
  return torch::from_blob(const_cast<float*>(m.ptr<float>()), {m.rows, m.cols, m.channels()}, torch::kFloat32)
      .permute({2, 0, 1})
      .clone();
}

// sRGB view -> [7, H, W]: RGB, its per-channel opening and the white top-hat of its luminance (mean of
// R, G, B), both with the architecture's disk: the classical filter's inputs (particle_filter.h).
torch::Tensor to_input(const Image& img, const AefArchitecture& arch, const std::string& where) {
  const cv::Mat rgb = rgb_mat(img, where);
  const int r = arch.opening_radius_px(img.width);
  const cv::Mat disk = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * r + 1, 2 * r + 1));
  cv::Mat opened, lum, tophat;
  cv::morphologyEx(rgb, opened, cv::MORPH_OPEN, disk, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  cv::transform(rgb, lum, cv::Matx13f(1.f / 3, 1.f / 3, 1.f / 3));
  cv::morphologyEx(lum, tophat, cv::MORPH_TOPHAT, disk, cv::Point(-1, -1), 1, cv::BORDER_REPLICATE);
  return torch::cat({hwc_to_chw(rgb).clamp(0.f, 1.f), hwc_to_chw(opened).clamp(0.f, 1.f), hwc_to_chw(tophat)}, 0);
}

torch::Tensor plane_to_tensor(const Image& img, int channels, const std::string& where, const Image& like) {
  if (img.width != like.width || img.height != like.height || img.channels < channels)
    throw InputError(where, "is " + img.to_string() + ", expected " + std::to_string(like.width) + "x" +
                                std::to_string(like.height) + " with " + std::to_string(channels) + " channel(s)");
  cv::Mat m(img.height, img.width, CV_32FC(img.channels), const_cast<float*>(img.data.data()));
  return hwc_to_chw(m).slice(0, 0, channels).clamp(0.f, 1.f).contiguous();
}

Image chw_to_image(const torch::Tensor& t, ColorSpace space) {
  const torch::Tensor hwc = t.permute({1, 2, 0}).contiguous();
  Image out(int(t.size(2)), int(t.size(1)), int(t.size(0)), space);
  std::memcpy(out.data.data(), hwc.data_ptr<float>(), out.data.size() * sizeof(float));
  return out;
}

}  // namespace

const char* to_string(AefPluginKind k) { return k == AefPluginKind::kDerain ? "derain" : "desnow"; }

void AefArchitecture::validate() const {
  if (channels < 1 || channels > 128) throw InputError("AEF architecture channels", "expected 1..128, got " + std::to_string(channels));
  if (bottleneck < 1 || bottleneck > 256)
    throw InputError("AEF architecture bottleneck", "expected 1..256, got " + std::to_string(bottleneck));
  if (residual_blocks < 0 || residual_blocks > 8)
    throw InputError("AEF architecture residual_blocks", "expected 0..8, got " + std::to_string(residual_blocks));
  if (!(prior_threshold > 0 && prior_threshold < 1))
    throw InputError("AEF architecture prior_threshold", "expected in (0, 1), got " + std::to_string(prior_threshold));
  if (!(prior_gain >= 0 && prior_gain <= 1000))
    throw InputError("AEF architecture prior_gain", "expected in [0, 1000], got " + std::to_string(prior_gain));
  if (!(opening_radius_px_at_300 > 0 && opening_radius_px_at_300 <= 64))
    throw InputError("AEF architecture opening_radius_px_at_300", "expected in (0, 64], got " + std::to_string(opening_radius_px_at_300));
}

int AefArchitecture::opening_radius_px(int width) const {
  return std::max(1, int(std::lround(opening_radius_px_at_300 * width / 300.0)));
}

namespace {
constexpr auto kAefArchitectureFields = [](auto& s, auto& f) {  // every key required
  f("channels", s.channels);
  f("bottleneck", s.bottleneck);
  f("residual_blocks", s.residual_blocks);
  f("opening_radius_px_at_300", s.opening_radius_px_at_300);
  f("prior_threshold", s.prior_threshold);
  f("prior_gain", s.prior_gain);
};
}  // namespace

Json AefArchitecture::to_json() const { return json_fields::write(*this, kAefArchitectureFields); }

AefArchitecture AefArchitecture::from_json(const JsonReader& r) {
  AefArchitecture a = json_fields::read(r, AefArchitecture{}, kAefArchitectureFields, json_fields::Absent::kError);
  a.validate();
  return a;
}

void AefTrainOptions::validate() const {
  arch.validate();
  if (iterations < 1) throw InputError("AEF training iterations", "expected at least 1, got " + std::to_string(iterations));
  if (batch < 1 || batch > 256) throw InputError("AEF training batch", "expected 1..256, got " + std::to_string(batch));
  if (crop < 16 || crop > 4096) throw InputError("AEF training crop", "expected 16..4096 px, got " + std::to_string(crop));
  if (!(learning_rate > 0 && learning_rate < 1))
    throw InputError("AEF training learning_rate", "expected in (0, 1), got " + std::to_string(learning_rate));
  if (!(ssim_weight >= 0 && ssim_weight <= 1))
    throw InputError("AEF training ssim_weight", "expected in [0, 1], got " + std::to_string(ssim_weight));
  if (!(alpha_weight >= 0 && alpha_weight <= 10))
    throw InputError("AEF training alpha_weight", "expected in [0, 10], got " + std::to_string(alpha_weight));
  if (threads < 0) throw InputError("AEF training threads", "expected >= 0, got " + std::to_string(threads));
}

struct AefPlugin::Impl : detail::NetworkState<AefArchitecture, AefNet> {
  AefPluginKind kind = AefPluginKind::kDerain;
};

AefPlugin::~AefPlugin() = default;
AefPlugin::AefPlugin(AefPlugin&&) noexcept = default;
AefPlugin& AefPlugin::operator=(AefPlugin&&) noexcept = default;

AefPlugin::AefPlugin(AefPluginKind kind, const AefArchitecture& arch, uint64_t seed) : impl_(std::make_unique<Impl>()) {
  arch.validate();
  impl_->kind = kind;
  impl_->arch = arch;
  torch::manual_seed(seed);  // libtorch's default initializers draw from the global CPU generator
  impl_->net = AefNet(arch);
  impl_->net->eval();
}

AefPluginKind AefPlugin::kind() const { return impl_->kind; }
const AefArchitecture& AefPlugin::architecture() const { return impl_->arch; }
const Json& AefPlugin::metadata() const { return impl_->metadata; }

int64_t AefPlugin::parameter_count() const {
  return detail::parameter_count(*impl_->net);
}

void AefPlugin::save(const std::string& stem, const Json& extra) const {
  detail::save_network(*impl_, stem, extra, kAefFormat, kAefFormatVersion, {{"plugin", to_string(impl_->kind)}});
}

AefPlugin AefPlugin::load(const std::string& stem, AefPluginKind expected) {
  const JsonReader r = detail::open_weights(stem, kAefFormat, kAefFormatVersion, "AEF plugin");
  const std::string plugin = r.get<std::string>("plugin");
  if (plugin != to_string(expected))
    throw InputError(r.where("plugin"), "expected the \"" + std::string(to_string(expected)) + "\" plugin, got \"" + plugin +
                                            "\"" + detail::kWeightsFix);
  AefPlugin p(expected, AefArchitecture::from_json(r.child("architecture")), 0);
  detail::load_weights(*p.impl_->net, r, stem);
  p.impl_->metadata = r.value();
  return p;
}

AefTrainRecord AefPlugin::train(const std::vector<AefExample>& examples, const AefTrainOptions& options) {
  AefTrainOptions o = options;
  o.arch = impl_->arch;  // the loss's alpha prior is the network's own
  o.validate();
  if (examples.empty()) throw InputError("AEF training set", "is empty");
  const auto start = std::chrono::steady_clock::now();
  torch::set_num_threads(o.threads > 0 ? o.threads : num_threads());
  std::vector<torch::Tensor> xs, ts, as;
  for (size_t i = 0; i < examples.size(); ++i) {
    const std::string where = "AEF training example " + std::to_string(i);
    const AefExample& e = examples[i];
    if (e.image.width < o.crop || e.image.height < o.crop)
      throw InputError(where, "image " + e.image.to_string() + " is smaller than the crop (" + std::to_string(o.crop) + " px)");
    xs.push_back(to_input(e.image, impl_->arch, where));
    ts.push_back(plane_to_tensor(e.target, 3, where + " target", e.image));
    as.push_back(plane_to_tensor(e.alpha, 1, where + " alpha", e.image));
  }
  AefNet& net = impl_->net;
  net->train();
  torch::optim::Adam adam(net->parameters(), torch::optim::AdamOptions(o.learning_rate));
  AefTrainRecord rec;
  rec.parameters = parameter_count();
  ProgressBar bar(std::string("train ") + to_string(impl_->kind), o.iterations);
  double window = 0;
  for (int it = 0; it < o.iterations; ++it) {
    // Examples, crops and flips keyed on (seed, iteration): the same run whatever the thread count.
    Rng rng(o.seed, kStreamAefBatch, uint64_t(it));
    std::vector<torch::Tensor> bx, bt, ba;
    for (int b = 0; b < o.batch; ++b) {
      const size_t k = rng.uniform_int(uint32_t(xs.size()));
      const int64_t y0 = rng.uniform_int(uint32_t(xs[k].size(1) - o.crop + 1));
      const int64_t x0 = rng.uniform_int(uint32_t(xs[k].size(2) - o.crop + 1));
      const bool flip = rng.uniform() < 0.5f;
      auto cut = [&](const torch::Tensor& t) {
        const torch::Tensor c = t.narrow(1, y0, o.crop).narrow(2, x0, o.crop);
        return flip ? c.flip({2}) : c;
      };
      bx.push_back(cut(xs[k]));
      bt.push_back(cut(ts[k]));
      ba.push_back(cut(as[k]));
    }
    detail::set_cosine_learning_rate(adam, o.learning_rate, it, o.iterations);
    adam.zero_grad();
    const torch::Tensor x = torch::stack(bx);
    const torch::Tensor loss = aef_loss(x, net->forward(x), torch::stack(bt), torch::stack(ba), o);
    loss.backward();
    adam.step();
    const double l = loss.item<double>();
    if (!std::isfinite(l))
      throw NumericalDivergence("AEF training loss became non-finite at iteration " + std::to_string(it) + " (lower --learning-rate)");
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

double AefPlugin::loss(const std::vector<AefExample>& examples, const AefTrainOptions& o) const {
  if (examples.empty()) throw InputError("AEF loss", "no examples");
  torch::NoGradGuard no_grad;
  double sum = 0;
  for (size_t i = 0; i < examples.size(); ++i) {
    const std::string where = "AEF loss example " + std::to_string(i);
    const AefExample& e = examples[i];
    const torch::Tensor x = to_input(e.image, impl_->arch, where).unsqueeze(0);
    AefTrainOptions lo = o;
    lo.arch = impl_->arch;
    sum += aef_loss(x, impl_->net->forward(x), plane_to_tensor(e.target, 3, where, e.image).unsqueeze(0),
                    plane_to_tensor(e.alpha, 1, where, e.image).unsqueeze(0), lo)
               .item<double>();
  }
  return sum / double(examples.size());
}

AefOutput AefPlugin::restore(const Image& image, const std::string& where) const {
  const torch::Tensor x = to_input(image, impl_->arch, where).unsqueeze(0);
  // One libtorch thread: its convolutions on 2 threads differ in the last bits from 1 thread; views
  // run in parallel instead (filter_dataset), so the output does not depend on the thread count.
  torch::set_num_threads(1);
  torch::NoGradGuard no_grad;
  const torch::Tensor out = impl_->net->forward(x);
  AefOutput r;
  r.restored = chw_to_image(composite(x, out, impl_->arch)[0].clamp(0.f, 1.f), ColorSpace::kSRGB);
  r.alpha = chw_to_image(torch::sigmoid(alpha_logit(x, out, impl_->arch))[0], ColorSpace::kLinear);
  return r;
}

}  // namespace weathergs::restoration::aef
