// The AEF's plugin selector without CLIP (docs/restoration.md). The paper picks a plugin by the cosine
// between a CLIP image embedding and the instruction text against a threshold theta (its eq. 4). Here a
// tiny weather embedder (a strided CNN over the full-resolution white top-hat of the luminance, global
// mean and max pooling, a linear layer, L2-normalized) is trained together with one learned prototype
// per instruction: "Remove snowy effect in the scene", "Remove rainy effect in the scene." (the
// released code's strings) and "none" (clear). Decision: the plugin prototype with the larger cosine
// is chosen when its cosine >= theta and exceeds the "none" cosine; otherwise no plugin runs. theta is
// calibrated on held-out generated views and stored with the weights. Per view (the paper) or per
// scene (the normalized mean embedding of the views).
//
// libtorch-free header: only weather_selector.cc includes it.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/json_reader.h"

namespace weathergs::restoration::aef {

inline constexpr const char* kSelectorFormat = "weathergs-weather-selector";
inline constexpr int kSelectorFormatVersion = 1;

// The prototypes, in the weights' order.
enum class WeatherClass { kSnow, kRain, kNone };
inline constexpr int kWeatherClasses = 3;
const char* to_string(WeatherClass c);  // "snow", "rain", "none"
inline constexpr const char* kInstructionDesnow = "Remove snowy effect in the scene";
inline constexpr const char* kInstructionDerain = "Remove rainy effect in the scene.";
inline constexpr const char* kInstructionNone = "none";
const char* instruction_of(WeatherClass c);
// An instruction text -> its class: the three strings above (case, surrounding spaces and a final
// period ignored), else a text that names exactly one of snow/rain ("remove the snow"); InputError
// listing the known instructions otherwise. Without CLIP no other text can be understood.
WeatherClass class_of_instruction(const std::string& text);

struct SelectorArchitecture {
  int width = 300;        // internal width (the height keeps the aspect ratio); the quick profile's own
  int channels = 8;       // features of the first conv (x1.5, x2 deeper)
  int embedding = 16;     // embedding dimension
  double tophat_radius_px_at_300 = 2.0;  // disk of the luminance top-hat input, scaled with the width
  void validate() const;  // InputError naming the field
  Json to_json() const;
  static SelectorArchitecture from_json(const JsonReader& r);
};

struct SelectorTrainOptions {
  SelectorArchitecture arch;
  int iterations = 1500;
  int batch = 16;
  double learning_rate = 3e-3;  // Adam, cosine-decayed to 5%
  double scale = 10;            // logits = scale * cosine (a fixed temperature)
  uint64_t seed = 1;
  int threads = 0;              // 0 = all cores
  bool progress = true;
  void validate() const;
};

struct SelectorExample {
  Image image;  // sRGB view
  WeatherClass label = WeatherClass::kNone;
};

struct SelectorTrainRecord {
  std::vector<double> loss_curve;  // mean loss per 50 iterations
  double seconds = 0;
  int64_t parameters = 0;
};

struct Selection {
  WeatherClass choice = WeatherClass::kNone;
  std::array<double, kWeatherClasses> cosine{};  // against each prototype, WeatherClass order
};

class WeatherSelector {
 public:
  WeatherSelector(const SelectorArchitecture& arch, uint64_t seed);
  ~WeatherSelector();
  WeatherSelector(WeatherSelector&&) noexcept;
  WeatherSelector& operator=(WeatherSelector&&) noexcept;

  // InputError naming the file and the fix (missing, corrupt, wrong format/version/architecture).
  static WeatherSelector load(const std::string& stem);
  void save(const std::string& stem, const Json& extra) const;

  const SelectorArchitecture& architecture() const;
  int64_t parameter_count() const;
  double theta() const;  // 0.5 until calibrated
  void set_theta(double theta);
  const Json& metadata() const;

  SelectorTrainRecord train(const std::vector<SelectorExample>& examples, const SelectorTrainOptions& options);

  // Unit-length embedding of an sRGB view (3 or 4 channels, at least 16x16). Runs on one libtorch
  // thread (tiny network); thread-count independent.
  std::vector<float> embed(const Image& image, const std::string& where) const;
  // The decision for one embedding (cosines against the prototypes, then theta).
  Selection select(const std::vector<float>& embedding) const;
  Selection select(const std::vector<float>& embedding, double theta) const;
  // Per scene: the normalized mean of the embeddings.
  static std::vector<float> mean_embedding(const std::vector<std::vector<float>>& embeddings);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace weathergs::restoration::aef
