// LPIPS v0.1 (Zhang et al. 2018) with the AlexNet trunk, run through OpenCV's dnn module from the
// ONNX export shipped in models/lpips (see its README for the exact conventions).
//
// The model is found by find_lpips_model over a list of candidate paths that the caller builds (the
// `weathergs` binary: --lpips-model, $WEATHERGS_LPIPS_MODEL, then its data directories;
// apps/resources.h). A path may name the .onnx file or its folder.
#pragma once

#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/image.h"

namespace weathergs::evaluator {

constexpr const char* kLpipsModelFile = "lpips_alex_v0.1.onnx";
// Smallest side AlexNet-LPIPS can score: conv1 (11x11, stride 4, pad 2) and two 3x3/2 max-pools
// need an input of at least 31 pixels.
constexpr int kLpipsMinSide = 31;

// Returns the model file of the first candidate that holds it (the .onnx file or a folder with it).
// Throws InputError listing every path searched and how to provide the model when none does.
std::string find_lpips_model(const std::vector<std::string>& candidates);

class Lpips {
 public:
  explicit Lpips(const std::string& onnx_path);
  ~Lpips();
  const std::string& model_path() const { return path_; }

  // LPIPS distance of two RGB images with sRGB-encoded values in [0, 1] (the network sees 2 v - 1,
  // i.e. uint8 / 127.5 - 1). Thread-safe (serialized; OpenCV parallelizes inside each layer).
  double distance(const Image& a, const Image& b);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string path_;
  std::mutex mutex_;
};

}  // namespace weathergs::evaluator
