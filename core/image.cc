#include "core/image.h"

#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/atomic_file.h"

namespace weathergs {

namespace fs = std::filesystem;
using namespace OIIO;

const char* to_string(ColorSpace c) { return c == ColorSpace::kSRGB ? "sRGB" : "linear"; }

Image::Image(int w, int h, int c, ColorSpace s, float fill)
    : width(w), height(h), channels(c), space(s), data(size_t(w) * size_t(h) * size_t(c), fill) {
  WGS_CHECK(w >= 0 && h >= 0 && c >= 1 && c <= 4);
}

std::string Image::to_string() const {
  return std::to_string(width) + "x" + std::to_string(height) + "x" + std::to_string(channels) +
         " " + weathergs::to_string(space);
}

float srgb_to_linear(float v) {
  return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}
float linear_to_srgb(float v) {
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.f / 2.4f) - 0.055f;
}

namespace {
Image convert(const Image& img, ColorSpace target, float (*fn)(float)) {
  Image out = img;
  if (img.space == target) return out;
  out.space = target;
  const int color = img.channels == 4 ? 3 : (img.channels == 2 ? 1 : img.channels);
  for (size_t p = 0; p < img.num_pixels(); ++p)
    for (int c = 0; c < color; ++c) {
      float& v = out.data[p * img.channels + c];
      v = fn(v);
    }
  return out;
}
}  // namespace

Image to_linear(const Image& img) { return convert(img, ColorSpace::kLinear, srgb_to_linear); }
Image to_srgb(const Image& img) { return convert(img, ColorSpace::kSRGB, linear_to_srgb); }

Image quantize_uint8(const Image& img) {
  Image out = to_srgb(img);
  for (float& v : out.data) {
    float c = std::isnan(v) ? 0.f : std::clamp(v, 0.f, 1.f);
    v = std::floor(c * 255.f + 0.5f) / 255.f;
  }
  return out;
}

Image to_rgb(const Image& img) {
  if (img.channels == 3) return img;
  Image out(img.width, img.height, 3, img.space);
  for (size_t p = 0; p < img.num_pixels(); ++p)
    for (int c = 0; c < 3; ++c)
      out.data[p * 3 + c] = img.data[p * img.channels + (img.channels >= 3 ? c : 0)];
  return out;
}

void require_finite(const Image& img, const std::string& where) {
  for (size_t i = 0; i < img.data.size(); ++i) {
    if (!std::isfinite(img.data[i])) {
      size_t p = i / img.channels;
      throw InputError(where, std::string("non-finite value (") +
                                  (std::isnan(img.data[i]) ? "NaN" : "inf") + ") at pixel (" +
                                  std::to_string(p % img.width) + ", " +
                                  std::to_string(p / img.width) + ") channel " +
                                  std::to_string(i % img.channels));
    }
  }
}

namespace {
std::string lower_ext(const std::string& path) {
  std::string e = fs::path(path).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e;
}

Image read_raw(const std::string& path, bool& is_float, std::vector<std::string>* names) {
  if (!fs::exists(path)) throw InputError(path, "file does not exist");
  auto in = ImageInput::open(path);
  if (!in) {
    std::string err = OIIO::geterror();
    throw InputError(path, "cannot read image" + (err.empty() ? std::string() : ": " + err));
  }
  const ImageSpec& spec = in->spec();
  if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0)
    throw InputError(path, "image has no pixels");
  if (spec.nchannels > 4)
    throw InputError(path, "expected 1..4 channels, got " + std::to_string(spec.nchannels));
  // A header may claim any size: refuse absurd ones before allocating (found by fuzz_image, whose
  // corrupt PNG headers asked for gigabytes).
  if (int64_t(spec.width) * spec.height > kMaxImagePixels || spec.width > kMaxImageSide || spec.height > kMaxImageSide)
    throw InputError(path, "image of " + std::to_string(spec.width) + "x" + std::to_string(spec.height) +
                               " pixels is larger than the supported " + std::to_string(kMaxImagePixels / 1000000) +
                               " megapixels (or " + std::to_string(kMaxImageSide) + " pixels a side)");
  is_float = spec.format.is_floating_point();
  if (names) *names = spec.channelnames;
  Image img(spec.width, spec.height, spec.nchannels, is_float ? ColorSpace::kLinear : ColorSpace::kSRGB);
  // Integer data converts to [0,1] floats (OIIO's normalized conversion).
  if (!in->read_image(0, 0, 0, spec.nchannels, TypeDesc::FLOAT, img.data.data())) {
    std::string err = in->geterror();
    throw InputError(path, "corrupt or truncated image" + (err.empty() ? "" : ": " + err));
  }
  in->close();
  return img;
}
}  // namespace

Image read_image(const std::string& path, const ImageReadOptions& options) {
  bool is_float = false;
  Image img = read_raw(path, is_float, nullptr);
  if (is_float) require_finite(img, path);
  return options.linear ? to_linear(img) : img;
}

void write_image(const std::string& path, const Image& img, const ImageWriteOptions& options) {
  WGS_CHECK(!img.empty());
  const std::string ext = lower_ext(path);
  const bool is_exr = ext == ".exr";
  PixelFormat format = options.format;
  if (is_exr && (format == PixelFormat::kUInt8 || format == PixelFormat::kUInt16))
    format = PixelFormat::kFloat32;
  if (!is_exr && (format == PixelFormat::kFloat32 || format == PixelFormat::kHalf))
    format = PixelFormat::kUInt8;

  const Image* src = &img;
  Image converted;
  if (!is_exr && img.space == ColorSpace::kLinear) {
    converted = to_srgb(img);
    src = &converted;
  }
  TypeDesc type = format == PixelFormat::kUInt8    ? TypeDesc::UINT8
                  : format == PixelFormat::kUInt16 ? TypeDesc::UINT16
                  : format == PixelFormat::kHalf   ? TypeDesc::HALF
                                                   : TypeDesc::FLOAT;
  ImageSpec spec(img.width, img.height, img.channels, type);
  if (!options.channel_names.empty()) {
    WGS_CHECK_EQ(int(options.channel_names.size()), img.channels);
    spec.channelnames = options.channel_names;
  }
  if (is_exr) {
    spec.attribute("compression", "zip");
    // OpenEXR stamps the write time (capDate) unless DateTime is set: clear it so that the same image
    // gives the same bytes (determinism of every output).
    spec.attribute("DateTime", "");
  }

  std::vector<float> clamped;
  const float* pixels = src->data.data();
  if (!is_exr) {  // integer output: clamp (OIIO would too) and map NaN to 0 deterministically
    clamped.resize(src->data.size());
    for (size_t i = 0; i < clamped.size(); ++i) {
      float v = src->data[i];
      clamped[i] = std::isnan(v) ? 0.f : std::clamp(v, 0.f, 1.f);
    }
    pixels = clamped.data();
  }

  write_file_atomic_with(path, [&](const std::string& tmp) {
    // OIIO picks the format from the extension, so the temp file keeps it: name.tmp-XXXX.png
    auto out = ImageOutput::create(path);
    if (!out) throw InputError(path, "unsupported image format: " + OIIO::geterror());
    if (!out->open(tmp, spec)) throw InputError(path, "cannot write: " + out->geterror());
    if (!out->write_image(TypeDesc::FLOAT, pixels)) throw InputError(path, "cannot write: " + out->geterror());
    if (!out->close()) throw InputError(path, "cannot write: " + out->geterror());
  });
}

Image read_depth(const std::string& path) {
  bool is_float = false;
  std::vector<std::string> names;
  Image raw = read_raw(path, is_float, &names);
  if (!is_float) throw InputError(path, "depth must be a float EXR (planar camera z in meters)");
  int channel = 0;
  for (size_t c = 0; c < names.size(); ++c)
    if (names[c] == "Z" || (names[c].size() > 2 && names[c].substr(names[c].size() - 2) == ".Z"))
      channel = int(c);
  Image depth(raw.width, raw.height, 1, ColorSpace::kLinear);
  for (size_t p = 0; p < raw.num_pixels(); ++p) {
    float z = raw.data[p * raw.channels + channel];
    if (std::isnan(z))
      throw InputError(path, "NaN depth at pixel (" + std::to_string(p % raw.width) + ", " +
                                 std::to_string(p / raw.width) + ")");
    // Camera z of a visible surface is positive (+inf for the sky); a negative or zero value would
    // otherwise pass silently (fog and rain then left such pixels untouched).
    if (!(z > 0.f))
      throw InputError(path, "depth " + std::to_string(z) + " at pixel (" + std::to_string(p % raw.width) + ", " +
                                 std::to_string(p / raw.width) + ") is not positive (planar camera z in meters)");
    depth.data[p] = z;  // is_background_depth (core/dataset_layout.h): kept as they are
  }
  return depth;
}

void write_depth(const std::string& path, const Image& depth) {
  WGS_CHECK_EQ(depth.channels, 1);
  Image d = depth;
  d.space = ColorSpace::kLinear;
  write_image(path, d, {PixelFormat::kFloat32, {"Z"}});
}

Image read_mask(const std::string& path) {
  Image raw = read_image(path);
  Image mask(raw.width, raw.height, 1, ColorSpace::kLinear);
  for (size_t p = 0; p < raw.num_pixels(); ++p)
    mask.data[p] = raw.data[p * raw.channels] >= 0.5f ? 1.f : 0.f;
  return mask;
}

void write_mask(const std::string& path, const Image& mask, float threshold) {
  WGS_CHECK_EQ(mask.channels, 1);
  Image m(mask.width, mask.height, 1, ColorSpace::kSRGB);
  for (size_t p = 0; p < mask.num_pixels(); ++p) m.data[p] = mask.data[p] >= threshold ? 1.f : 0.f;
  write_image(path, m);
}

}  // namespace weathergs
