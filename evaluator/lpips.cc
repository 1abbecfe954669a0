#include "evaluator/lpips.h"

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>

#include <filesystem>

#include "evaluator/metrics.h"

namespace weathergs::evaluator {

namespace fs = std::filesystem;

namespace {
std::optional<std::string> as_model_file(const std::string& p) {
  std::error_code ec;
  if (fs::is_regular_file(p, ec)) return p;
  if (fs::is_directory(p, ec) && fs::is_regular_file(fs::path(p) / kLpipsModelFile, ec))
    return (fs::path(p) / kLpipsModelFile).string();
  return std::nullopt;
}
}  // namespace

std::string find_lpips_model(const std::vector<std::string>& candidates) {
  std::string searched;
  for (const std::string& c : candidates) {
    if (auto f = as_model_file(c)) return *f;
    searched += "\n  " + c;
  }
  throw InputError(candidates.size() == 1 ? candidates.front() : std::string("lpips"),
                   std::string("cannot find the LPIPS model ") + kLpipsModelFile + ". Searched:" +
                       (searched.empty() ? std::string(" nothing") : searched) +
                       "\nProvide it with --lpips-model PATH or the environment variable WEATHERGS_LPIPS_MODEL "
                       "(weathergs ships them as models/lpips, installed into share/weathergs/models/lpips), or skip LPIPS "
                       "explicitly with --no-lpips.");
}

struct Lpips::Impl {
  cv::dnn::Net net;
};

Lpips::Lpips(const std::string& onnx_path) : impl_(std::make_unique<Impl>()), path_(onnx_path) {
  try {
    impl_->net = cv::dnn::readNetFromONNX(onnx_path);
  } catch (const cv::Exception& e) {
    throw InputError(onnx_path, std::string("cannot load the LPIPS ONNX model: ") + e.what());
  }
  if (impl_->net.empty()) throw InputError(onnx_path, "cannot load the LPIPS ONNX model (empty network)");
  impl_->net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  impl_->net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
}

Lpips::~Lpips() = default;

namespace {
cv::Mat to_blob(const Image& img) {
  const int sizes[4] = {1, 3, img.height, img.width};
  cv::Mat blob(4, sizes, CV_32F);
  float* p = blob.ptr<float>();
  const size_t plane = img.num_pixels();
  for (size_t i = 0; i < plane; ++i)
    for (int c = 0; c < 3; ++c) p[size_t(c) * plane + i] = 2.f * img.data[i * img.channels + size_t(c)] - 1.f;
  return blob;
}
}  // namespace

double Lpips::distance(const Image& a, const Image& b) {
  require_comparable(a, b, nullptr, "lpips");
  if (a.channels != 3) throw InputError("lpips", "expected RGB images, got " + a.to_string());
  if (a.width < kLpipsMinSide || a.height < kLpipsMinSide)
    throw InputError("lpips", "image " + std::to_string(a.width) + "x" + std::to_string(a.height) +
                                  " is too small for LPIPS-alex (each side must be at least " +
                                  std::to_string(kLpipsMinSide) + " pixels); use --no-lpips");
  const Image sa = to_srgb(a), sb = to_srgb(b);
  cv::Mat in0 = to_blob(sa), in1 = to_blob(sb);
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    impl_->net.setInput(in0, "in0");
    impl_->net.setInput(in1, "in1");
    cv::Mat out = impl_->net.forward("lpips");
    return double(out.ptr<float>()[0]);
  } catch (const cv::Exception& e) {
    throw InternalError(std::string("LPIPS forward pass failed: ") + e.what());
  }
}

}  // namespace weathergs::evaluator
