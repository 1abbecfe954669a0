#include "restoration/led/led_training.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>

#include "core/dataset.h"
#include "core/error.h"
#include "core/json_reader.h"

namespace weathergs::restoration::led {

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

// The truth of `views` (lens_mask_or_zero) into m.truth, and whether any of it marks a drop.
void read_truth(const Dataset& ds, const std::vector<std::string>& views, LedHeldOutMap& m) {
  for (const std::string& v : views) {
    m.truth.push_back(lens_mask_or_zero(ds, ds.camera(v)));
    for (float x : m.truth.back().data) m.has_drops |= x > 0.5f;
  }
}

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

LedHeldOutMap held_out_map(const LensDetector& led, const std::string& dataset) {
  const Dataset ds = read_dataset(dataset);
  LedHeldOutMap m{dataset_name(dataset), {}, {}, false};
  std::vector<Image> views;
  for (const std::string& v : ds.split("train")) views.push_back(read_image(ds.path(ImageKind::kImages, v)));
  read_truth(ds, ds.split("train"), m);
  m.attention = mean_attention(led, views, dataset);
  return m;
}

SavedLedMap read_saved_led_map(const std::string& detect_dir) {
  const fs::path report_path = fs::path(detect_dir) / kDetectReportFile;
  if (!fs::exists(report_path))
    throw InputError(detect_dir, std::string("is not a finished `weathergs detect` output: no ") + kDetectReportFile);
  const JsonReader r = JsonReader::from_file(report_path.string());
  const Json& j = r.value();
  using namespace detect_key;
  if (j.value(kFormat, "") != kDetectFormat) throw InputError(r.where(kFormat), std::string("expected \"") + kDetectFormat + "\"");
  if (!j.contains(kAttention) || j[kAttention].is_null())
    throw InputError(report_path.string(), "was written without --save-attention: run `weathergs detect ... --save-attention` again");
  if (j.value(kAveraging, std::string()) != to_string(LedAveraging::kTrainViews))
    throw InputError(r.where(kAveraging), std::string("expected \"") + to_string(LedAveraging::kTrainViews) +
                                               "\": a calibration scores the one mask averaged over the training views");
  const std::vector<std::string> views = r.get<std::vector<std::string>>(kAveragedViews);
  if (views.empty()) throw InputError(r.where(kAveragedViews), "is empty");
  const std::string dataset = r.get<std::string>(kDataset);
  const Dataset ds = read_dataset(dataset);
  SavedLedMap out;
  out.weights_sha256 = j.value(kWeightsSha256, "");
  out.adaptation = j.contains(kAdaptation) ? j[kAdaptation] : Json();
  out.map.name = dataset_name(dataset);
  if (views != ds.split("train"))
    throw InputError(r.where(kAveragedViews), "differs from the training split of " + dataset + ": the dataset changed since");
  read_truth(ds, views, out.map);
  // Every view's saved map is the same averaged one in train-views mode: the first stands for all.
  const std::string map_path = (fs::path(detect_dir) / j[kAttention].get<std::string>() / (views[0] + layout::kImageExt)).string();
  out.map.attention = read_image(map_path);  // 16-bit PNG: the value is the attention
  const Camera& c = ds.camera(views[0]);
  if (out.map.attention.channels != 1 || out.map.attention.width != c.width || out.map.attention.height != c.height)
    throw InputError(map_path, "is " + out.map.attention.to_string() + ", expected one channel of the view's size");
  out.map.attention.space = ColorSpace::kLinear;
  return out;
}

void LedCalibrationOptions::validate() const {
  mask.validate();
  if (min_precision && !(*min_precision > 0 && *min_precision <= 1))
    throw InputError("LED calibration min_precision", "expected in (0, 1], got " + std::to_string(*min_precision));
}

LedCalibration calibrate_led(const std::vector<LedHeldOutMap>& held_out, const LedCalibrationOptions& o) {
  o.validate();
  if (held_out.empty()) throw InputError("LED calibration", "needs at least one held-out dataset");
  int with_drops = 0;
  for (const LedHeldOutMap& m : held_out) with_drops += m.has_drops;
  if (with_drops == 0) throw InputError("LED calibration", "none of the held-out datasets has drops (masks/lens): nothing to calibrate on");
  const LedMaskOptions& mo = o.mask;
  auto score_rule = [&](const LedHeldOutMap& c, LedThresholdRule rule, double t, const LedPeakRule& peak, int dilations) {
    LedMaskOptions m = mo;
    m.rule = rule;
    m.threshold = t;
    m.peak = peak;
    m.dilate_iterations = dilations;
    return score_lens_masks(c.name, {attention_to_mask(c.attention, m)}, c.truth);
  };
  // The mean IoU and precision over the held-out datasets with drops (the calibration's objective and
  // its optional constraint).
  struct Means {
    double iou = 0, precision = 0;
  };
  auto means = [&](LedThresholdRule rule, double t, const LedPeakRule& peak, int dilations) {
    Means s;
    for (const LedHeldOutMap& c : held_out)
      if (c.has_drops) {
        const LedScore r = score_rule(c, rule, t, peak, dilations);
        s.iou += r.iou, s.precision += r.precision;
      }
    s.iou /= with_drops, s.precision /= with_drops;
    return s;
  };
  double best_precision_seen = 0;
  auto admissible = [&](const Means& m) {
    best_precision_seen = std::max(best_precision_seen, m.precision);
    return !o.min_precision || m.precision >= *o.min_precision;
  };
  auto none_admissible = [&](const std::string& what) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "no %s of the grid reaches a mean precision of %.3f on the held-out datasets (the best: %.3f)",
                  what.c_str(), *o.min_precision, best_precision_seen);
    return InputError("LED calibration min_precision", buf);
  };
  LedCalibration best;
  best.mean_iou = -1;
  const int fixed = mo.dilate_iterations.value_or(kReleasedCodeDilations);
  const int lo = o.search_dilations ? 0 : fixed, hi = o.search_dilations ? kMaxCalibratedDilations : fixed;
  for (int dilations = lo; dilations <= hi; ++dilations)
    for (int k = 0; k <= 36; ++k) {  // kThresholdGrid
      const double t = 0.05 + 0.025 * k;
      const Means m = means(LedThresholdRule::kAbove, t, LedPeakRule{}, dilations);
      if (admissible(m) && m.iou > best.mean_iou + 1e-12)
        best.mean_iou = m.iou, best.mean_precision = m.precision, best.threshold = t, best.dilate_iterations = dilations;
    }
  if (best.mean_iou < 0) throw none_admissible("threshold");
  for (const LedHeldOutMap& c : held_out)
    best.scores.push_back(score_rule(c, LedThresholdRule::kAbove, best.threshold, LedPeakRule{}, best.dilate_iterations));
  if (!o.search_peak) return best;
  best.peak_mean_iou = -1;
  best_precision_seen = 0;
  for (int l = 2; l <= 6; ++l)  // kPeakGrid
    for (int sd = l; sd <= 7; ++sd)
      for (int f = 0; f <= 8; ++f) {
        const LedPeakRule p{l / 10.0, sd / 10.0, (10 + f) / 20.0};
        const Means m = means(LedThresholdRule::kPeak, best.threshold, p, best.dilate_iterations);
        if (admissible(m) && m.iou > best.peak_mean_iou + 1e-12) best.peak_mean_iou = m.iou, best.peak_mean_precision = m.precision, best.peak = p;
      }
  if (!best.peak) throw none_admissible("peak rule");
  for (const LedHeldOutMap& c : held_out)
    best.peak_scores.push_back(score_rule(c, LedThresholdRule::kPeak, best.threshold, *best.peak, best.dilate_iterations));
  return best;
}

LedCalibration calibrate_led(const LensDetector& led, const std::vector<std::string>& held_out, const LedMaskOptions& mo,
                             bool search_dilations, bool search_peak) {
  if (held_out.empty()) throw InputError("LED calibration", "needs at least one held-out dataset");
  std::vector<LedHeldOutMap> maps;  // the mean attention once per dataset; only the rule varies
  for (const std::string& d : held_out) maps.push_back(held_out_map(led, d));
  LedCalibrationOptions o;
  o.mask = mo;
  o.search_dilations = search_dilations;
  o.search_peak = search_peak;
  return calibrate_led(maps, o);
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

std::string objective_text(const std::optional<double>& min_precision) {
  std::string t = ", maximizing the mean IoU of the averaged mask over held-out datasets with drops";
  if (min_precision) {
    char buf[96];
    std::snprintf(buf, sizeof buf, " among the rules whose mean precision there is at least %.3f", *min_precision);
    t += buf;
  }
  return t;
}

Json peak_json(const LedCalibration& c) {
  return {{"grid", kPeakGrid},
          {"rule", c.peak->to_json()},
          {"mean_iou", c.peak_mean_iou},
          {"mean_precision", c.peak_mean_precision},
          {"scores", scores_json(c.peak_scores)}};
}

Json calibration_json(const LedCalibration& c, const Json& held_out_names, const std::string& grid,
                      const std::optional<double>& min_precision) {
  Json j{{"held_out", held_out_names},
         {"grid", grid + objective_text(min_precision)},
         {"dilate_iterations", c.dilate_iterations},
         {"threshold", c.threshold},
         {"mean_iou", c.mean_iou},
         {"mean_precision", c.mean_precision},
         {"scores", scores_json(c.scores)}};
  if (min_precision) j["min_precision"] = *min_precision;
  if (c.peak) j["peak_rule"] = peak_json(c);
  return j;
}

}  // namespace

Json calibration_json(const LedCalibration& c, const std::vector<std::string>& held_out, const std::string& grid) {
  Json held = Json::array();
  for (const std::string& d : held_out) held.push_back(dataset_name(d));
  return calibration_json(c, held, grid, std::nullopt);
}

void RecalibrateLedOptions::validate() const {
  if (held_out.empty() == maps.empty())
    throw InputError("calibrate-led", "needs either --held-out datasets or --maps (detect outputs with saved attention), not both");
  if (adapted && maps.empty())
    throw InputError("calibrate-led --adapted", "needs --maps: the outputs of `weathergs detect --adapt --save-attention`");
  if (adapted && !search_peak) throw InputError("calibrate-led --adapted", "calibrates the adapted peak rule: add --peak");
  if (width && !maps.empty())
    throw InputError("calibrate-led --width", "needs --held-out: saved maps were made at the weights' own width");
  if (min_precision && !(*min_precision > 0 && *min_precision <= 1))
    throw InputError("calibrate-led --min-precision", "expected in (0, 1], got " + std::to_string(*min_precision));
}

LedCalibration recalibrate_led(const std::string& weights_stem, const std::string& out_stem, const RecalibrateLedOptions& o) {
  o.validate();
  LensDetector led = LensDetector::load(weights_stem);
  const int width_before = led.architecture().width;
  if (o.width) led.set_width(*o.width);
  LedCalibrationOptions co;
  co.mask.dilate_iterations = led.dilate_iterations();
  co.search_peak = o.search_peak;
  co.min_precision = o.min_precision;
  std::vector<LedHeldOutMap> maps;
  Json names = Json::array(), adaptations = Json::array();
  if (!o.held_out.empty()) {
    for (const std::string& d : o.held_out) maps.push_back(held_out_map(led, d));
  } else {
    const std::string sha = led.metadata().value("weights_sha256", "");
    for (const std::string& dir : o.maps) {
      SavedLedMap m = read_saved_led_map(dir);
      if (m.weights_sha256 != sha)
        throw InputError(dir, "was made by other weights (sha256 " + m.weights_sha256.substr(0, 8) + "..., " + weights_stem +
                                  " has " + sha.substr(0, 8) + "...): run detect again with --weights " + weights_stem);
      const bool made_adapted = !m.adaptation.is_null();
      if (o.adapted != made_adapted)
        throw InputError(dir, o.adapted ? "was made without --adapt: --adapted calibrates on maps of `detect --adapt`"
                                        : "was made with --adapt: calibrate the adapted rule with --adapted");
      if (o.adapted)
        adaptations.push_back({{"dataset", m.map.name},
                               {"iterations", m.adaptation.value("iterations", Json())},
                               {"layouts", m.adaptation.contains("layouts") ? Json(m.adaptation["layouts"].size()) : Json()}});
      maps.push_back(std::move(m.map));
    }
  }
  for (const LedHeldOutMap& m : maps) names.push_back(m.name);
  const LedCalibration c = calibrate_led(maps, co);
  Json extra = led.metadata();
  if (o.adapted) {
    led.set_adapted_peak_rule(c.peak);
    if (extra.contains("adapted_calibration")) extra["previous_adapted_calibration"] = extra["adapted_calibration"];
    Json a = peak_json(c);
    a["grid"] = std::string(kPeakGrid) + objective_text(o.min_precision);
    a["held_out"] = names;
    a["dilate_iterations"] = c.dilate_iterations;
    a["adaptations"] = adaptations;
    if (o.min_precision) a["min_precision"] = *o.min_precision;
    a["command"] = o.command;
    extra["adapted_calibration"] = a;
  } else {
    apply_calibration(led, c);
    if (extra.contains("calibration")) extra["previous_calibration"] = extra["calibration"];
    extra["calibration"] = calibration_json(c, names, kThresholdGrid, o.min_precision);
    extra["calibration"]["command"] = o.command;
    if (led.architecture().width != width_before) extra["calibration"]["width_changed_from"] = width_before;
  }
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
  // The calibration needs drops: fail before the training, not after it.
  if (!held_out.empty()) {
    bool drops = false;
    for (size_t i = 0; i < held_out.size() && !drops; ++i) {
      const Dataset ds = read_dataset(held_out[i]);
      LedHeldOutMap m;
      read_truth(ds, ds.split("train"), m);
      drops = m.has_drops;
    }
    if (!drops) throw InputError("train-led --held-out", "none of the held-out datasets has drops (masks/lens): nothing to calibrate on");
  }
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

}  // namespace weathergs::restoration::led
