// Float image with 1..4 interleaved channels. Values are either sRGB-encoded (as stored in 8/16-bit
// PNG and JPEG, scaled to [0,1]) or linear radiance (EXR, and everything that composites light).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/error.h"

namespace weathergs {

enum class ColorSpace { kSRGB, kLinear };
const char* to_string(ColorSpace c);

struct Image {
  int width = 0;
  int height = 0;
  int channels = 0;
  ColorSpace space = ColorSpace::kSRGB;
  std::vector<float> data;  // row-major, interleaved: data[(y * width + x) * channels + c]

  Image() = default;
  Image(int width, int height, int channels, ColorSpace space = ColorSpace::kSRGB, float fill = 0.f);

  bool empty() const { return data.empty(); }
  size_t num_pixels() const { return size_t(width) * size_t(height); }
  float& at(int x, int y, int c = 0) { return data[(size_t(y) * width + x) * channels + c]; }
  float at(int x, int y, int c = 0) const { return data[(size_t(y) * width + x) * channels + c]; }
  bool same_shape(const Image& o) const {
    return width == o.width && height == o.height && channels == o.channels;
  }
  std::string to_string() const;  // "600x400x3 sRGB"
};

// Exact IEC 61966-2-1 transfer functions (piecewise, threshold 0.04045 / 0.0031308).
float srgb_to_linear(float v);
float linear_to_srgb(float v);
Image to_linear(const Image& img);  // no-op copy when already linear; alpha (4th channel) untouched
Image to_srgb(const Image& img);

// Quantizes to 8 bits as a PNG writer would (round half up, clamp to [0,1]) and back to float:
// the protocol step of the evaluator (NerfBaselines quantizes both images before scoring).
Image quantize_uint8(const Image& img);

// Keeps the first `channels` channels (drops alpha); a 1-channel image is replicated to 3.
Image to_rgb(const Image& img);

// Throws InputError(where, ...) if any value is NaN or infinite, naming the first such pixel.
void require_finite(const Image& img, const std::string& where);

struct ImageReadOptions {
  // Convert to linear radiance regardless of the file's encoding.
  bool linear = false;
};

// Largest image the readers accept (a header may claim any size): 50 megapixels (800 MB as RGBA
// float), 65536 a side.
inline constexpr int64_t kMaxImagePixels = 50000000;
inline constexpr int kMaxImageSide = 65536;

// Reads PNG (8/16-bit), JPEG, EXR, ... through OpenImageIO. Integer formats are sRGB-encoded in
// [0,1]; float formats (EXR) are linear. Errors (missing, truncated, corrupt) are InputError.
Image read_image(const std::string& path, const ImageReadOptions& options = {});

enum class PixelFormat { kUInt8, kUInt16, kFloat32, kHalf };
struct ImageWriteOptions {
  PixelFormat format = PixelFormat::kUInt8;  // PNG: uint8/uint16; EXR: float32/half
  // Channel names for EXR (e.g. {"Z"} for depth); empty means R,G,B,A by count.
  std::vector<std::string> channel_names;
};

// Writes atomically (temp file + rename). 8/16-bit output expects sRGB-encoded values in [0,1]
// (clamped); a linear image is converted to sRGB first. EXR output is written as is.
void write_image(const std::string& path, const Image& img, const ImageWriteOptions& options = {});

// Planar depth (camera z, meters) from an EXR: channel "Z", else R. Background: is_background_depth
// (core/dataset_layout.h: >= 1e9 or +inf).
Image read_depth(const std::string& path);
void write_depth(const std::string& path, const Image& depth);
// 8-bit single-channel mask: returns 1 channel with values in {0,1} (>= 128 counts as set).
Image read_mask(const std::string& path);
void write_mask(const std::string& path, const Image& mask, float threshold = 0.5f);

}  // namespace weathergs
