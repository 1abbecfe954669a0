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
                             bool search_dilations, bool search_peak) {
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
  auto score_rule = [&](const Cached& c, LedThresholdRule rule, double t, const LedPeakRule& peak, int dilations) {
    LedMaskOptions m = mo;
    m.rule = rule;
    m.threshold = t;
    m.peak = peak;
    m.dilate_iterations = dilations;
    return score_lens_masks(c.name, {attention_to_mask(c.attention, m)}, c.gts);
  };
  // The mean IoU over the held-out datasets with drops (the calibration's objective).
  auto mean_iou = [&](LedThresholdRule rule, double t, const LedPeakRule& peak, int dilations) {
    double sum = 0;
    int n = 0;
    for (const Cached& c : cache)
      if (c.has_drops) sum += score_rule(c, rule, t, peak, dilations).iou, ++n;
    return n > 0 ? sum / n : 0;
  };
  LedCalibration best;
  best.mean_iou = -1;
  const int fixed = mo.dilate_iterations.value_or(kReleasedCodeDilations);
  const int lo = search_dilations ? 0 : fixed, hi = search_dilations ? kMaxCalibratedDilations : fixed;
  for (int dilations = lo; dilations <= hi; ++dilations)
    for (int k = 0; k <= 36; ++k) {  // kThresholdGrid
      const double t = 0.05 + 0.025 * k;
      const double mean = mean_iou(LedThresholdRule::kAbove, t, LedPeakRule{}, dilations);
      if (mean > best.mean_iou + 1e-12) best.mean_iou = mean, best.threshold = t, best.dilate_iterations = dilations;
    }
  for (const Cached& c : cache)
    best.scores.push_back(score_rule(c, LedThresholdRule::kAbove, best.threshold, LedPeakRule{}, best.dilate_iterations));
  if (!search_peak) return best;
  best.peak_mean_iou = -1;
  for (int l = 2; l <= 6; ++l)  // kPeakGrid
    for (int sd = l; sd <= 7; ++sd)
      for (int f = 0; f <= 8; ++f) {
        const LedPeakRule p{l / 10.0, sd / 10.0, (10 + f) / 20.0};
        const double mean = mean_iou(LedThresholdRule::kPeak, best.threshold, p, best.dilate_iterations);
        if (mean > best.peak_mean_iou + 1e-12) best.peak_mean_iou = mean, best.peak = p;
      }
  for (const Cached& c : cache)
    best.peak_scores.push_back(score_rule(c, LedThresholdRule::kPeak, best.threshold, *best.peak, best.dilate_iterations));
  return best;
}

namespace {

Json scores_json(const std::vector<LedScore>& scores) {
  Json out = Json::array();
  for (const LedScore& s : scores)
    out.push_back({{"dataset", s.dataset}, {"iou", s.iou}, {"precision", s.precision}, {"recall", s.recall},
                   {"gt_fraction", s.gt_fraction}, {"mask_fraction", s.mask_fraction}});
  return out;
}

void apply_calibration(LensDetector& led, const LedCalibration& c) {
  led.set_threshold(c.threshold);
  led.set_dilate_iterations(c.dilate_iterations);
  led.set_peak_rule(c.peak);
}

}  // namespace

Json calibration_json(const LedCalibration& c, const std::vector<std::string>& held_out, const std::string& grid) {
  Json held = Json::array();
  for (const std::string& d : held_out) held.push_back(dataset_name(d));
  Json j{{"held_out", held},
         {"grid", grid + ", maximizing the mean IoU of the averaged mask over held-out datasets with drops"},
         {"dilate_iterations", c.dilate_iterations},
         {"threshold", c.threshold},
         {"mean_iou", c.mean_iou},
         {"scores", scores_json(c.scores)}};
  if (c.peak)
    j["peak_rule"] = {{"grid", kPeakGrid}, {"rule", c.peak->to_json()}, {"mean_iou", c.peak_mean_iou}, {"scores", scores_json(c.peak_scores)}};
  return j;
}

LedCalibration recalibrate_led(const std::string& weights_stem, const std::vector<std::string>& held_out,
                               const std::string& out_stem, bool search_peak, const std::string& command,
                               std::optional<int> width) {
  if (held_out.empty()) throw InputError("calibrate-led", "needs at least one --held-out dataset");
  LensDetector led = LensDetector::load(weights_stem);
  const int width_before = led.architecture().width;
  if (width) led.set_width(*width);
  LedMaskOptions mo;
  mo.dilate_iterations = led.dilate_iterations();
  const LedCalibration c = calibrate_led(led, held_out, mo, false, search_peak);
  apply_calibration(led, c);
  Json extra = led.metadata();
  if (extra.contains("calibration")) extra["previous_calibration"] = extra["calibration"];
  extra["calibration"] = calibration_json(c, held_out, kThresholdGrid);
  extra["calibration"]["command"] = command;
  if (led.architecture().width != width_before) extra["calibration"]["width_changed_from"] = width_before;
  led.save(out_stem, extra);
  return c;
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
  for (size_t g = 0; g < train_datasets.size(); ++g)
    for (LedExample& e : read_led_examples(train_datasets[g])) {
      e.group = int(g);
      examples.push_back(std::move(e));
    }
  result.examples = examples.size();
  if (!o.ignore_mask.empty()) {
    const Image ignore = read_mask(o.ignore_mask);
    for (LedExample& e : examples) {
      if (ignore.width != e.image.width || ignore.height != e.image.height)
        throw InputError(o.ignore_mask, "is " + ignore.to_string() + ", the views are " + e.image.to_string());
      e.weight = Image(e.image.width, e.image.height, 1, ColorSpace::kLinear);
      for (size_t i = 0; i < e.weight.data.size(); ++i)
        e.weight.data[i] = std::max(e.mask.data[i] > 0.5f ? 1.f : 0.f, 1.f - ignore.data[i]);
    }
  }
  LensDetector led = o.init.empty() ? LensDetector(o.train.arch, o.train.seed) : LensDetector::load(o.init);
  LedTrainOptions train = o.train;
  train.arch = led.architecture();
  result.record = led.train(examples, train);
  examples.clear();
  if (!held_out.empty()) {
    result.calibration = calibrate_led(led, held_out, o.mask, o.calibrate_dilations, o.calibrate_peak);
    apply_calibration(led, result.calibration);
  }
  Json names = Json::array();
  for (const std::string& d : train_datasets) names.push_back(dataset_name(d));
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
        {"drop_balance_area", o.train.drop_balance_area},
        {"seed", o.train.seed},
        {"threads", o.train.threads},
        {"seconds", result.record.seconds},
        {"loss_per_50_iterations", result.record.loss_curve}}},
      {"calibration", calibration_json(result.calibration, held_out,
                                       std::string(kThresholdGrid) +
                                           (o.calibrate_dilations ? " x 0.." + std::to_string(kMaxCalibratedDilations) + " dilations" : ""))}};
  led.save(out_stem, extra);
  return result;
}

}  // namespace weathergs::restoration
