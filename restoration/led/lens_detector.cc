// The only translation unit of the LED that includes libtorch (~17 s to compile).
#include "restoration/led/lens_detector.h"

#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgproc.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/json_fields.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/rng.h"
#include "core/sha256.h"
#include "restoration/torch_weights.h"

namespace weathergs::restoration::led {

namespace fs = std::filesystem;
namespace nn = torch::nn;
namespace F = torch::nn::functional;

namespace {

constexpr uint64_t kStreamLedBatch = 0x4c4544424154ull;  // "LEDBAT": which examples, flips

using detail::ResidualBlock;

constexpr int kInputChannels = 4;  // RGB + sharpness (to_tensor)

// One recurrent step: cat(RGB, sharpness, A_{t-1}) -> conv (full res) -> strided conv -> residual blocks ->
// ConvLSTM -> upsample -> conv over cat(state, full-res features) -> sigmoid.
struct LedNetImpl : nn::Module {
  LedArchitecture arch;
  const bool pool_att;    // the mean attention over the call's views is an input (LedViewPooling)
  const bool pool_state;  // and the ConvLSTM's mean state
  nn::Conv2d in{nullptr}, down{nullptr}, lstm{nullptr}, out{nullptr};
  nn::ModuleList blocks;

  explicit LedNetImpl(const LedArchitecture& a)
      : arch(a),
        pool_att(a.view_pooling != LedViewPooling::kNone),
        pool_state(a.view_pooling == LedViewPooling::kAttentionAndState) {
    const int ch = a.channels;
    in = register_module("in", nn::Conv2d(nn::Conv2dOptions(kInputChannels + 1 + (pool_att ? 1 : 0), ch, 3).padding(1)));
    down = register_module("down", nn::Conv2d(nn::Conv2dOptions(ch, ch, 3).padding(1).stride(2)));
    blocks = register_module("blocks", nn::ModuleList());
    for (int b = 0; b < a.residual_blocks; ++b) blocks->push_back(ResidualBlock(ch, 1 << b));
    lstm = register_module("lstm", nn::Conv2d(nn::Conv2dOptions((pool_state ? 3 : 2) * ch, 4 * ch, 3).padding(1)));
    out = register_module("out", nn::Conv2d(nn::Conv2dOptions(2 * ch, 1, 3).padding(1)));
    // Prior: drops cover a small part of a view. Starting the output at sigmoid(-2) ~ 0.12 (RetinaNet's
    // prior initialization) keeps training from first collapsing to "no drop anywhere".
    torch::NoGradGuard no_grad;
    out->bias.fill_(-2.0);
  }

  // The mean over the views (dimension 0) of the call, repeated for every view.
  static torch::Tensor view_mean(const torch::Tensor& t) { return t.mean(0, true).expand_as(t); }

  // x: [B, 4, H, W] in [0, 1]; with view pooling the B views are one dataset's. Returns the N
  // attention maps [B, 1, H, W].
  std::vector<torch::Tensor> forward(const torch::Tensor& x) {
    const int64_t B = x.size(0), H = x.size(2), W = x.size(3);
    torch::Tensor att = torch::full({B, 1, H, W}, 0.5f);
    torch::Tensor h, c;
    std::vector<torch::Tensor> maps;
    for (int t = 0; t < arch.steps; ++t) {
      const torch::Tensor input = pool_att ? torch::cat({x, att, view_mean(att)}, 1) : torch::cat({x, att}, 1);
      const torch::Tensor full = torch::relu(in(input));
      torch::Tensor f = torch::relu(down(full));
      for (const auto& b : *blocks) f = b->as<ResidualBlock>()->forward(f);
      if (t == 0) {
        h = torch::zeros_like(f);
        c = torch::zeros_like(f);
      }
      const torch::Tensor gates_in = pool_state ? torch::cat({f, h, view_mean(h)}, 1) : torch::cat({f, h}, 1);
      const std::vector<torch::Tensor> g = lstm(gates_in).chunk(4, 1);
      c = torch::sigmoid(g[1]) * c + torch::sigmoid(g[0]) * torch::tanh(g[2]);
      h = torch::sigmoid(g[3]) * torch::tanh(c);
      const torch::Tensor up =
          F::interpolate(h, F::InterpolateFuncOptions().size(std::vector<int64_t>{H, W}).mode(torch::kBilinear).align_corners(false));
      att = torch::sigmoid(out(torch::cat({up, full}, 1)));
      maps.push_back(att);
    }
    return maps;
  }
};
TORCH_MODULE(LedNet);

int internal_height(const LedArchitecture& a, int width, int height) {
  return std::max(8, int(std::lround(double(a.width) * height / width)));
}

// sRGB image (3 or 4 channels) -> [4, h, w] float tensor at the internal size: RGB by area resampling,
// and a sharpness channel, the mean |Laplacian| of the luminance taken at the full resolution and then
// area-averaged. A defocused drop is above all a region without fine texture; that cue lives in the
// frequencies the downsampling removes, so it is measured before (the network may work at reduced
// resolution; this keeps what the drop looks like at full resolution).
torch::Tensor to_tensor(const Image& img, int w, int h, const std::string& where) {
  if (img.empty() || img.channels < 3)
    throw InputError(where, "expected an RGB image (3 or 4 channels), got " + img.to_string());
  require_finite(img, where);
  cv::Mat m(img.height, img.width, CV_32FC(img.channels), const_cast<float*>(img.data.data()));
  cv::Mat rgb;
  if (img.channels == 4) cv::cvtColor(m, rgb, cv::COLOR_RGBA2RGB); else rgb = m;
  cv::Mat grey, lap, small_rgb, small_sharp;
  cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
  cv::Laplacian(grey, lap, CV_32F, 1, 1.0, 0.0, cv::BORDER_REFLECT);
  lap = cv::abs(lap);
  cv::resize(rgb, small_rgb, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  cv::resize(lap, small_sharp, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  torch::Tensor t = torch::empty({4, h, w}, torch::kFloat32);
  const torch::Tensor c = torch::from_blob(small_rgb.ptr<float>(), {h, w, 3}, torch::kFloat32).permute({2, 0, 1});
  t.slice(0, 0, 3).copy_(c);
  // kSharpnessGain maps a typical textured region (mean |Laplacian| ~ 0.05-0.1) to ~0.5-1.
  constexpr float kSharpnessGain = 8.f;
  t[3].copy_(torch::from_blob(small_sharp.ptr<float>(), {h, w}, torch::kFloat32) * kSharpnessGain);
  return t.clamp(0.f, 1.f).contiguous();
}

torch::Tensor mask_to_tensor(const Image& mask, int w, int h) {
  cv::Mat m(mask.height, mask.width, CV_32FC1, const_cast<float*>(mask.data.data()));
  cv::Mat small;
  cv::resize(m, small, cv::Size(w, h), 0, 0, cv::INTER_AREA);
  return torch::from_blob(small.ptr<float>(), {1, h, w}, torch::kFloat32).clone().clamp(0.f, 1.f);
}

// One example's share of attention_loss over a batch whose normalizer (the weights' sum, or the
// batch's element count without weights) is `normalizer`: the shares of a batch sum to its loss.
torch::Tensor attention_loss_share(const std::vector<torch::Tensor>& maps, const torch::Tensor& target, double theta,
                                   const torch::Tensor& weight, double normalizer) {
  torch::Tensor loss = torch::zeros({});
  const int n = int(maps.size());
  for (int t = 0; t < n; ++t) {
    const torch::Tensor sq = (maps[size_t(t)] - target).square();
    const torch::Tensor sum = weight.defined() ? (sq * weight).sum() : sq.sum();
    loss = loss + std::pow(theta, n - 1 - t) * sum / normalizer;
  }
  return loss;
}

// sum_t theta^(N-1-t) MSE(A_t, M); with `weight` (same shape as the target) each MSE is the weighted mean.
torch::Tensor attention_loss(const std::vector<torch::Tensor>& maps, const torch::Tensor& target, double theta,
                             const torch::Tensor& weight = {}) {
  torch::Tensor loss = torch::zeros({});
  const int n = int(maps.size());
  for (int t = 0; t < n; ++t) {
    const torch::Tensor mse = weight.defined() ? ((maps[size_t(t)] - target).square() * weight).sum() / weight.sum().clamp_min(1e-6)
                                               : F::mse_loss(maps[size_t(t)], target);
    loss = loss + std::pow(theta, n - 1 - t) * mse;
  }
  return loss;
}

// The per-pixel weights of the drop-size balance for one internal-size mask [1, h, w]: pixels of a
// drop (8-connected region where the mask is > 0, its soft rim included) of area A < R get
// sqrt(R / A), capped at kMaxDropWeight; the rest 1.
torch::Tensor drop_balance_weights(const torch::Tensor& mask, double area_ref) {
  const int h = int(mask.size(1)), w = int(mask.size(2));
  const torch::Tensor m = mask.contiguous();
  cv::Mat drop(h, w, CV_8UC1);
  const float* mp = m.data_ptr<float>();
  for (int i = 0; i < h * w; ++i) drop.data[i] = mp[i] > 0.f ? 1 : 0;
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(drop, labels, stats, centroids, 8, CV_32S);
  std::vector<float> component_weight(size_t(n), 1.f);
  for (int c = 1; c < n; ++c) {
    const double area = stats.at<int>(c, cv::CC_STAT_AREA);
    component_weight[size_t(c)] = float(std::clamp(std::sqrt(area_ref / area), 1.0, kMaxDropWeight));
  }
  torch::Tensor out = torch::empty({1, h, w}, torch::kFloat32);
  float* op = out.data_ptr<float>();
  const int32_t* lp = labels.ptr<int32_t>();
  for (int i = 0; i < h * w; ++i) op[i] = component_weight[size_t(lp[i])];
  return out;
}

// Images and masks of `examples` at the internal size (one aspect ratio for all); InputError names
// `where` + the example's index.
void examples_to_tensors(const std::vector<LedExample>& examples, const LedArchitecture& arch, const std::string& where,
                         std::vector<torch::Tensor>& xs, std::vector<torch::Tensor>& ms) {
  const int W = arch.width;
  const int H = internal_height(arch, examples[0].image.width, examples[0].image.height);
  for (size_t i = 0; i < examples.size(); ++i) {
    const LedExample& e = examples[i];
    const std::string name = where + std::to_string(i);
    if (e.mask.channels != 1 || e.mask.width != e.image.width || e.mask.height != e.image.height)
      throw InputError(name, "mask " + e.mask.to_string() + " does not match image " + e.image.to_string());
    if (internal_height(arch, e.image.width, e.image.height) != H)
      throw InputError(name, "has another aspect ratio than the first example (" + e.image.to_string() + ")");
    xs.push_back(to_tensor(e.image, W, H, name));
    ms.push_back(mask_to_tensor(e.mask, W, H));
  }
}

}  // namespace

void LedArchitecture::validate() const {
  if (steps < 1 || steps > 16) throw InputError("LED architecture steps", "expected 1..16, got " + std::to_string(steps));
  if (width < 16 || width > 2048) throw InputError("LED architecture width", "expected 16..2048 px, got " + std::to_string(width));
  if (channels < 1 || channels > 256) throw InputError("LED architecture channels", "expected 1..256, got " + std::to_string(channels));
  if (residual_blocks < 0 || residual_blocks > 8)
    throw InputError("LED architecture residual_blocks", "expected 0..8, got " + std::to_string(residual_blocks));
}

const char* to_string(LedViewPooling p) {
  switch (p) {
    case LedViewPooling::kNone: return "none";
    case LedViewPooling::kAttention: return "attention";
    case LedViewPooling::kAttentionAndState: return "attention+state";
  }
  WGS_CHECK(false);
  return "";
}

const char* to_string(LedGradient g) {
  switch (g) {
    case LedGradient::kBatched: return "batched";
    case LedGradient::kPerExample: return "per-example";
  }
  WGS_CHECK(false);
  return "";
}

LedViewPooling parse_led_view_pooling(const std::string& s, const std::string& where) {
  for (LedViewPooling p : {LedViewPooling::kNone, LedViewPooling::kAttention, LedViewPooling::kAttentionAndState})
    if (s == to_string(p)) return p;
  throw InputError(where, "expected none, attention or attention+state, got \"" + s + "\"");
}

namespace {
// Every key required; view_pooling is written only when used, so a per-view network's JSON reads as before.
constexpr auto kLedArchitectureFields = [](auto& s, auto& f) {
  f("steps", s.steps);
  f("width", s.width);
  f("channels", s.channels);
  f("residual_blocks", s.residual_blocks);
  f("view_pooling", s.view_pooling,
    json_fields::OneOf{LedViewPooling::kNone, LedViewPooling::kAttention, LedViewPooling::kAttentionAndState},
    json_fields::OmitIf{LedViewPooling::kNone});
};
constexpr auto kPeakRuleFields = [](auto& s, auto& f) {
  f("low", s.low, json_fields::Bounds{0, 1});
  f("seed", s.seed, json_fields::Bounds{0, 1});
  f("fraction", s.fraction, json_fields::Bounds{0, 1});
};
}  // namespace

Json LedArchitecture::to_json() const { return json_fields::write(*this, kLedArchitectureFields); }

LedArchitecture LedArchitecture::from_json(const JsonReader& r) {
  LedArchitecture a = json_fields::read(r, LedArchitecture{}, kLedArchitectureFields, json_fields::Absent::kError);
  a.validate();
  return a;
}

void LedTrainOptions::validate() const {
  arch.validate();
  if (iterations < 1) throw InputError("LED training iterations", "expected at least 1, got " + std::to_string(iterations));
  if (batch < 1 || batch > 256) throw InputError("LED training batch", "expected 1..256, got " + std::to_string(batch));
  if (!(learning_rate > 0 && learning_rate < 1))
    throw InputError("LED training learning_rate", "expected in (0, 1), got " + std::to_string(learning_rate));
  if (!(theta > 0 && theta <= 1)) throw InputError("LED training theta", "expected in (0, 1], got " + std::to_string(theta));
  if (!(drop_balance_area >= 0 && drop_balance_area <= 1e6))
    throw InputError("LED training drop_balance_area", "expected 0 (off) to 1e6 internal pixels, got " + std::to_string(drop_balance_area));
  if (!(colour_jitter >= 0 && colour_jitter <= 0.5))
    throw InputError("LED training colour_jitter", "expected in [0, 0.5], got " + std::to_string(colour_jitter));
  if (threads < 0) throw InputError("LED training threads", "expected >= 0, got " + std::to_string(threads));
  if (gradient == LedGradient::kPerExample && arch.view_pooling != LedViewPooling::kNone)
    throw InputError("LED training gradient", "per-example gradients need a per-view network (view_pooling none): "
                                              "a view-pooling network's batch is one forward pass");
}

void LedPeakRule::validate() const {
  if (!(low > 0 && low <= seed && seed < 1))
    throw InputError("LED peak rule", "expected 0 < low <= seed < 1, got low " + std::to_string(low) + ", seed " + std::to_string(seed));
  if (!(fraction > 0 && fraction <= 1))
    throw InputError("LED peak rule fraction", "expected in (0, 1], got " + std::to_string(fraction));
}

Json LedPeakRule::to_json() const { return json_fields::write(*this, kPeakRuleFields); }

LedPeakRule LedPeakRule::from_json(const JsonReader& r) {
  LedPeakRule p = json_fields::read(r, LedPeakRule{}, kPeakRuleFields, json_fields::Absent::kError);
  p.validate();
  return p;
}

struct LensDetector::Impl : detail::NetworkState<LedArchitecture, LedNet> {
  double threshold = 0.5;
  int dilate_iterations = kReleasedCodeDilations;
  std::optional<LedPeakRule> peak_rule;
  std::optional<LedPeakRule> adapted_peak_rule;
};

LensDetector::LensDetector(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
LensDetector::~LensDetector() = default;
LensDetector::LensDetector(LensDetector&&) noexcept = default;
LensDetector& LensDetector::operator=(LensDetector&&) noexcept = default;

LensDetector::LensDetector(const LedArchitecture& arch, uint64_t seed) : impl_(std::make_unique<Impl>()) {
  arch.validate();
  impl_->arch = arch;
  torch::manual_seed(seed);  // libtorch's default initializers draw from the global CPU generator
  impl_->net = LedNet(arch);
  impl_->net->eval();
}

LensDetector LensDetector::clone() const {
  LensDetector c(impl_->arch, 0);
  {
    torch::NoGradGuard no_grad;
    const auto src = impl_->net->named_parameters(), dst = c.impl_->net->named_parameters();
    for (const auto& p : src) dst[p.key()].copy_(p.value());
    const auto src_b = impl_->net->named_buffers(), dst_b = c.impl_->net->named_buffers();
    for (const auto& b : src_b) dst_b[b.key()].copy_(b.value());
  }
  c.impl_->threshold = impl_->threshold;
  c.impl_->dilate_iterations = impl_->dilate_iterations;
  c.impl_->peak_rule = impl_->peak_rule;
  c.impl_->adapted_peak_rule = impl_->adapted_peak_rule;
  c.impl_->metadata = impl_->metadata;
  return c;
}

const LedArchitecture& LensDetector::architecture() const { return impl_->arch; }
void LensDetector::set_width(int width) {
  LedArchitecture a = impl_->arch;
  a.width = width;
  a.validate();
  impl_->arch = a;
}
double LensDetector::threshold() const { return impl_->threshold; }
void LensDetector::set_threshold(double t) {
  if (!(t > 0 && t < 1)) throw InputError("LED threshold", "expected in (0, 1), got " + std::to_string(t));
  impl_->threshold = t;
}
int checked_dilations(int n) {
  if (n < 0 || n > kMaxDilations)
    throw InputError("LED dilate_iterations", "expected 0.." + std::to_string(kMaxDilations) + ", got " + std::to_string(n));
  return n;
}
int LensDetector::dilate_iterations() const { return impl_->dilate_iterations; }
void LensDetector::set_dilate_iterations(int n) { impl_->dilate_iterations = checked_dilations(n); }
const std::optional<LedPeakRule>& LensDetector::peak_rule() const { return impl_->peak_rule; }
void LensDetector::set_peak_rule(const std::optional<LedPeakRule>& rule) {
  if (rule) rule->validate();
  impl_->peak_rule = rule;
}
const std::optional<LedPeakRule>& LensDetector::adapted_peak_rule() const { return impl_->adapted_peak_rule; }
void LensDetector::set_adapted_peak_rule(const std::optional<LedPeakRule>& rule) {
  if (rule) rule->validate();
  impl_->adapted_peak_rule = rule;
}
const Json& LensDetector::metadata() const { return impl_->metadata; }

int64_t LensDetector::parameter_count() const {
  return detail::parameter_count(*impl_->net);
}

void LensDetector::save(const std::string& stem, const Json& extra) const {
  detail::save_network(*impl_, stem, extra, kLedFormat, kLedFormatVersion,
                       {{"threshold", impl_->threshold},
                        {"dilate_iterations", impl_->dilate_iterations},
                        {"peak_rule", impl_->peak_rule ? impl_->peak_rule->to_json() : Json()},
                        {"adapted_peak_rule", impl_->adapted_peak_rule ? impl_->adapted_peak_rule->to_json() : Json()}});
}

LensDetector LensDetector::load(const std::string& stem) {
  const JsonReader r = detail::open_weights(stem, kLedFormat, kLedFormatVersion, "LED");
  const LedArchitecture arch = LedArchitecture::from_json(r.child("architecture"));
  LensDetector d(arch, 0);
  detail::load_weights(*d.impl_->net, r, stem);
  d.impl_->threshold = r.get_number("threshold", 1e-6, 1 - 1e-6);
  d.impl_->dilate_iterations = int(r.get_number_or("dilate_iterations", kReleasedCodeDilations, 0, kMaxDilations));
  if (r.has("peak_rule")) d.impl_->peak_rule = LedPeakRule::from_json(r.child("peak_rule"));
  if (r.has("adapted_peak_rule")) d.impl_->adapted_peak_rule = LedPeakRule::from_json(r.child("adapted_peak_rule"));
  d.impl_->metadata = r.value();
  return d;
}

namespace {

// LedGradient::kPerExample: sets every parameter's gradient to that of the batch loss, computed as the
// sum, in batch order, of the gradients of each example's share (attention_loss_share), each taken
// with one intra-op thread on whichever worker runs it (`threads` at a time). Neither the split nor
// the sum depends on the thread count, so neither do the weights. Returns the batch loss.
double per_example_gradients(LedNet& net, const std::vector<torch::Tensor>& bx, const std::vector<torch::Tensor>& bm,
                             const std::vector<torch::Tensor>& bw, double theta, int threads) {
  const size_t n = bx.size();
  double normalizer = 0;
  if (bw.empty()) {
    for (const torch::Tensor& m : bm) normalizer += double(m.numel());
  } else {
    for (const torch::Tensor& w : bw) normalizer += w.sum().item<double>();  // batch order
    normalizer = std::max(normalizer, 1e-6);
  }
  const std::vector<torch::Tensor> params = net->parameters();
  std::vector<std::vector<torch::Tensor>> grads(n);
  std::vector<double> shares(n, 0.0);
  auto one = [&](int64_t b) {
    torch::set_num_threads(1);  // this worker's own OpenMP setting: one intra-op thread
    const size_t i = size_t(b);
    const torch::Tensor share = attention_loss_share(net->forward(bx[i].unsqueeze(0)), bm[i].unsqueeze(0), theta,
                                                     bw.empty() ? torch::Tensor() : bw[i].unsqueeze(0), normalizer);
    grads[i] = torch::autograd::grad({share}, params);
    shares[i] = share.item<double>();
  };
  if (threads == 1) {
    for (size_t b = 0; b < n; ++b) one(int64_t(b));
  } else {
    parallel_for(0, int64_t(n), one);
  }
  double loss = 0;
  for (size_t p = 0; p < params.size(); ++p) {
    torch::Tensor g = grads[0][p].clone();
    for (size_t b = 1; b < n; ++b) g.add_(grads[b][p]);
    params[p].mutable_grad() = g;
  }
  for (double s : shares) loss += s;
  return loss;
}

}  // namespace

LedTrainRecord LensDetector::train(const std::vector<LedExample>& examples, const LedTrainOptions& o) {
  o.validate();
  if (examples.empty()) throw InputError("LED training set", "is empty");
  const auto start = std::chrono::steady_clock::now();
  const bool per_example = o.gradient == LedGradient::kPerExample;
  if (per_example && impl_->arch.view_pooling != LedViewPooling::kNone)
    throw InputError("LED training gradient", "per-example gradients need a per-view network, this one pools over the views");
  const int threads = o.threads > 0 ? o.threads : num_threads();
  torch::set_num_threads(per_example ? 1 : threads);
  std::vector<torch::Tensor> xs, ms;
  examples_to_tensors(examples, impl_->arch, "LED training example ", xs, ms);
  std::vector<torch::Tensor> ws;
  // Per-pixel loss weights: the drop-size balance, the examples' own weights, or their product.
  const bool weighted = std::any_of(examples.begin(), examples.end(), [](const LedExample& e) { return !e.weight.data.empty(); });
  if (o.drop_balance_area > 0)
    for (const torch::Tensor& m : ms) ws.push_back(drop_balance_weights(m, o.drop_balance_area));
  if (weighted)
    for (size_t i = 0; i < examples.size(); ++i) {
      const LedExample& e = examples[i];
      if (e.weight.data.empty()) {
        if (ws.size() <= i) ws.push_back(torch::ones_like(ms[i]));
        continue;
      }
      if (e.weight.channels != 1 || e.weight.width != e.image.width || e.weight.height != e.image.height)
        throw InputError("LED training example " + std::to_string(i), "weight " + e.weight.to_string() + " does not match image " + e.image.to_string());
      const torch::Tensor w = mask_to_tensor(e.weight, int(ms[i].size(2)), int(ms[i].size(1)));
      if (ws.size() <= i) ws.push_back(w);
      else ws[i] = ws[i] * w;
    }
  const bool use_weights = !ws.empty();
  LedNet& net = impl_->net;
  net->train();
  torch::optim::Adam adam(net->parameters(), torch::optim::AdamOptions(o.learning_rate));
  LedTrainRecord rec;
  rec.parameters = parameter_count();
  ProgressBar bar("train LED", o.iterations);
  double window = 0;
  // A view-pooling network trains on `batch` distinct views of one group (dataset) per batch, all
  // flipped alike (a lens-fixed drop stays where it is in every view).
  const bool pooled = impl_->arch.view_pooling != LedViewPooling::kNone;
  std::vector<std::vector<size_t>> groups;
  if (pooled) {
    std::map<int, std::vector<size_t>> by_group;
    for (size_t i = 0; i < examples.size(); ++i) by_group[examples[i].group].push_back(i);
    for (auto& [g, members] : by_group) {
      if (int(members.size()) < o.batch)
        throw InputError("LED training group " + std::to_string(g),
                         "has " + std::to_string(members.size()) + " views, fewer than the batch of " + std::to_string(o.batch) +
                             " a view-pooling network trains on");
      groups.push_back(std::move(members));
    }
  }
  for (int it = 0; it < o.iterations; ++it) {
    // Batch and flips keyed on (seed, iteration): the same run whatever the thread count.
    Rng rng(o.seed, kStreamLedBatch, uint64_t(it));
    std::vector<torch::Tensor> bx, bm, bw;
    std::vector<size_t> picks;
    bool group_flip = false;
    if (pooled) {
      std::vector<size_t> members = groups[rng.uniform_int(uint32_t(groups.size()))];
      for (int b = 0; b < o.batch; ++b) {  // partial Fisher-Yates: distinct views
        const size_t j = size_t(b) + rng.uniform_int(uint32_t(members.size() - size_t(b)));
        std::swap(members[size_t(b)], members[j]);
        picks.push_back(members[size_t(b)]);
      }
      group_flip = rng.uniform() < 0.5f;
    }
    for (int b = 0; b < o.batch; ++b) {
      const size_t k = pooled ? picks[size_t(b)] : rng.uniform_int(uint32_t(xs.size()));
      const bool flip = pooled ? group_flip : rng.uniform() < 0.5f;
      torch::Tensor x = flip ? xs[k].flip({2}) : xs[k];
      if (o.colour_jitter > 0) {
        const float j = float(o.colour_jitter);
        const float overall = 1.f + j * (2.f * rng.uniform() - 1.f);
        float gain[4];
        for (int c = 0; c < 3; ++c) gain[c] = overall * (1.f + j * (2.f * rng.uniform() - 1.f));
        gain[3] = overall;
        x = (x * torch::tensor({gain[0], gain[1], gain[2], gain[3]}).view({4, 1, 1})).clamp(0.f, 1.f);
      }
      bx.push_back(x);
      bm.push_back(flip ? ms[k].flip({2}) : ms[k]);
      if (use_weights) bw.push_back(flip ? ws[k].flip({2}) : ws[k]);
    }
    detail::set_cosine_learning_rate(adam, o.learning_rate, it, o.iterations);
    adam.zero_grad();
    double l = 0;
    if (per_example) {
      l = per_example_gradients(net, bx, bm, bw, o.theta, threads);
    } else {
      const torch::Tensor loss = attention_loss(net->forward(torch::stack(bx)), torch::stack(bm), o.theta,
                                                use_weights ? torch::stack(bw) : torch::Tensor());
      loss.backward();
      l = loss.item<double>();
    }
    adam.step();
    if (!std::isfinite(l)) throw NumericalDivergence("LED training loss became non-finite at iteration " + std::to_string(it) + " (lower --learning-rate)");
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

std::vector<Image> LensDetector::attention(const std::vector<Image>& images, const std::string& where) const {
  if (images.empty()) return {};
  const int iw = images[0].width, ih = images[0].height;
  const int W = impl_->arch.width, H = internal_height(impl_->arch, iw, ih);
  std::vector<torch::Tensor> xs;
  for (const Image& img : images) {
    if (img.width != iw || img.height != ih)
      throw InputError(where, "images of one batch differ in size (" + img.to_string() + " vs " + images[0].to_string() + ")");
    xs.push_back(to_tensor(img, W, H, where));
  }
  // One intra-op thread: this network is too small for libtorch's threading to pay (bench_restoration,
  // 600x400: 9.5 ms per view with 1 thread, 23.7 ms with 2).
  torch::set_num_threads(1);
  torch::NoGradGuard no_grad;
  const std::vector<torch::Tensor> maps = impl_->net->forward(torch::stack(xs));
  torch::Tensor mean = maps[0];
  for (size_t t = 1; t < maps.size(); ++t) mean = mean + maps[t];
  mean = (mean / double(maps.size())).contiguous();
  std::vector<Image> out;
  for (size_t i = 0; i < images.size(); ++i) {
    const torch::Tensor a = mean[int64_t(i)][0].contiguous();
    cv::Mat small(H, W, CV_32FC1, a.data_ptr<float>());
    cv::Mat big;
    cv::resize(small, big, cv::Size(iw, ih), 0, 0, cv::INTER_LINEAR);
    Image m(iw, ih, 1, ColorSpace::kLinear);
    std::memcpy(m.data.data(), big.ptr<float>(), m.data.size() * sizeof(float));
    for (float& v : m.data) v = std::clamp(v, 0.f, 1.f);
    out.push_back(std::move(m));
  }
  return out;
}

Image LensDetector::attention(const Image& image, const std::string& where) const {
  return attention(std::vector<Image>{image}, where).front();
}

double LensDetector::loss(const std::vector<LedExample>& examples, double theta) const {
  if (examples.empty()) throw InputError("LED loss", "no examples");
  std::vector<torch::Tensor> bx, bm;
  examples_to_tensors(examples, impl_->arch, "LED loss example ", bx, bm);
  torch::NoGradGuard no_grad;
  return attention_loss(impl_->net->forward(torch::stack(bx)), torch::stack(bm), theta).item<double>();
}

}  // namespace weathergs::restoration::led
