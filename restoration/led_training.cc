#include "restoration/led_training.h"

#include <cmath>
#include <filesystem>
#include <set>

#include "core/dataset.h"
#include "core/error.h"
#include "core/json_reader.h"

namespace weathergs::restoration {

namespace fs = std::filesystem;

namespace {

Image lens_mask_or_zero(const Dataset& ds, const Camera& c) {
  if (!ds.has(ImageKind::kLensMask)) return Image(c.width, c.height, 1, ColorSpace::kLinear);
  const std::string path = ds.path(ImageKind::kLensMask, c.name);
  if (!fs::exists(path)) throw InputError(path, "missing: the dataset has masks/lens but not view " + c.name);
  Image m = read_mask(path);
  if (m.width != c.width || m.height != c.height) throw InputError(path, "is " + m.to_string() + ", expected the view's size");
  return m;
}

std::string dataset_name(const std::string& dir) { return fs::path(dir).lexically_normal().filename().string(); }

}  // namespace

std::vector<LedExample> read_led_examples(const std::string& dataset) {
  const Dataset ds = read_dataset(dataset);
  std::vector<LedExample> out;
  for (const Camera& c : ds.cameras) {
    const std::string path = ds.path(ImageKind::kImages, c.name);
    Image img = read_image(path);
    if (img.width != c.width || img.height != c.height) throw InputError(path, "is " + img.to_string() + ", expected the view's size");
    out.push_back({to_rgb(img), lens_mask_or_zero(ds, c)});
  }
  return out;
}

LedCalibration calibrate_led(const LensDetector& led, const std::vector<std::string>& held_out, const LedMaskOptions& mo,
                             bool search_dilations) {
  if (held_out.empty()) throw InputError("LED calibration", "needs at least one held-out dataset");
  // The mean attention is computed once per dataset; only the threshold varies.
  struct Cached {
    std::string name;
    Image attention;
    std::vector<Image> gts;
    bool has_drops = false;
  };
  std::vector<Cached> cache;
  for (const std::string& d : held_out) {
    const Dataset ds = read_dataset(d);
    Cached c{dataset_name(d), {}, {}, false};
    std::vector<Image> views;
    for (const std::string& v : ds.split("train")) {
      views.push_back(read_image(ds.path(ImageKind::kImages, v)));
      c.gts.push_back(lens_mask_or_zero(ds, ds.camera(v)));
      for (float x : c.gts.back().data) c.has_drops |= x > 0.5f;
    }
    c.attention = mean_attention(led, views, d);
    cache.push_back(std::move(c));
  }
  auto score = [&](const Cached& c, double t, int dilations) {
    return score_lens_masks(c.name, {attention_to_mask(c.attention, t, dilations, mo)}, c.gts);
  };
  LedCalibration best;
  best.mean_iou = -1;
  const int fixed = mo.dilate_iterations.value_or(kReleasedCodeDilations);
  const int lo = search_dilations ? 0 : fixed, hi = search_dilations ? kMaxCalibratedDilations : fixed;
  for (int dilations = lo; dilations <= hi; ++dilations)
    for (int k = 0; k <= 36; ++k) {
      const double t = 0.05 + 0.025 * k;
      double sum = 0;
      int n = 0;
      for (const Cached& c : cache)
        if (c.has_drops) sum += score(c, t, dilations).iou, ++n;
      const double mean = n > 0 ? sum / n : 0;
      if (mean > best.mean_iou + 1e-12) best.mean_iou = mean, best.threshold = t, best.dilate_iterations = dilations;
    }
  for (const Cached& c : cache) best.scores.push_back(score(c, best.threshold, best.dilate_iterations));
  return best;
}

TrainLedResult train_led(const std::vector<std::string>& train_datasets, const std::vector<std::string>& held_out,
                         const std::string& out_stem, const TrainLedOptions& o) {
  o.train.validate();
  o.mask.validate();
  if (train_datasets.empty()) throw InputError("train-led", "no training datasets given");
  const std::set<std::string> train_set(train_datasets.begin(), train_datasets.end());
  for (const std::string& h : held_out)
    if (train_set.count(h)) throw InputError(h, "is both a training and a held-out dataset");
  TrainLedResult result;
  std::vector<LedExample> examples;
  for (const std::string& d : train_datasets)
    for (LedExample& e : read_led_examples(d)) examples.push_back(std::move(e));
  result.examples = examples.size();
  LensDetector led(o.train.arch, o.train.seed);
  result.record = led.train(examples, o.train);
  examples.clear();
  if (!held_out.empty()) {
    result.calibration = calibrate_led(led, held_out, o.mask, o.calibrate_dilations);
    led.set_threshold(result.calibration.threshold);
    led.set_dilate_iterations(result.calibration.dilate_iterations);
  }
  Json scores = Json::array();
  for (const LedScore& s : result.calibration.scores)
    scores.push_back({{"dataset", s.dataset}, {"iou", s.iou}, {"precision", s.precision}, {"recall", s.recall},
                      {"gt_fraction", s.gt_fraction}, {"mask_fraction", s.mask_fraction}});
  Json names = Json::array(), held = Json::array();
  for (const std::string& d : train_datasets) names.push_back(dataset_name(d));
  for (const std::string& d : held_out) held.push_back(dataset_name(d));
  const Json extra{
      {"model", "Lens Effect Detector (attentive-recurrent, AttentiveGAN-style)"},
      {"command", o.command},
      {"training",
       {{"datasets", names},
        {"examples", result.examples},
        {"iterations", o.train.iterations},
        {"batch", o.train.batch},
        {"learning_rate", o.train.learning_rate},
        {"theta", o.train.theta},
        {"colour_jitter", o.train.colour_jitter},
        {"seed", o.train.seed},
        {"threads", o.train.threads},
        {"seconds", result.record.seconds},
        {"loss_per_50_iterations", result.record.loss_curve}}},
      {"calibration",
       {{"held_out", held},
        {"grid", std::string("0.05..0.95 step 0.025") +
                     (o.calibrate_dilations ? " x 0.." + std::to_string(kMaxCalibratedDilations) + " dilations" : "") +
                     ", maximizing the mean IoU of the averaged mask over held-out datasets with drops"},
        {"dilate_iterations", result.calibration.dilate_iterations},
        {"threshold", result.calibration.threshold},
        {"mean_iou", result.calibration.mean_iou},
        {"scores", scores}}}};
  led.save(out_stem, extra);
  return result;
}

}  // namespace weathergs::restoration
