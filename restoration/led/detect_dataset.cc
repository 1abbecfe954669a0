#include "restoration/led/detect_dataset.h"

#include <cstdio>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <set>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/error.h"
#include "core/json_reader.h"
#include "core/parallel.h"
#include "core/progress.h"

namespace weathergs::restoration::led {

namespace fs = std::filesystem;

const char* to_string(LedAveraging a) { return a == LedAveraging::kPerView ? "per-view" : "train-views"; }
const char* to_string(LedThresholdRule r) {
  switch (r) {
    case LedThresholdRule::kBand: return "band";
    case LedThresholdRule::kPeak: return "peak";
    default: return "above";
  }
}

void LedMaskOptions::validate() const {
  if (threshold && !(*threshold > 0 && *threshold < 1))
    throw InputError("LED threshold", "expected in (0, 1), got " + std::to_string(*threshold));
  if (!(band_lo >= 0 && band_lo < band_hi && band_hi <= 1))
    throw InputError("LED band", "expected 0 <= lo < hi <= 1, got [" + std::to_string(band_lo) + ", " + std::to_string(band_hi) + "]");
  if (dilate_iterations) checked_dilations(*dilate_iterations);
  if (peak) peak->validate();
}

LedMaskOptions LedMaskOptions::resolved(const LensDetector& led) const {
  LedMaskOptions r = *this;
  if (!r.rule) r.rule = led.peak_rule() ? LedThresholdRule::kPeak : LedThresholdRule::kAbove;
  if (!r.threshold) r.threshold = led.threshold();
  if (!r.peak) r.peak = led.peak_rule().value_or(LedPeakRule{});
  if (!r.dilate_iterations) r.dilate_iterations = *r.rule == LedThresholdRule::kBand ? kReleasedCodeDilations : led.dilate_iterations();
  r.validate();
  return r;
}

namespace {

// kPeak: label the 8-connected regions of m >= low, take each region's maximum, keep the pixels at or
// above max(low, fraction * maximum) of the regions whose maximum reaches seed.
cv::Mat peak_relative_mask(const cv::Mat& a, const LedPeakRule& p) {
  cv::Mat above = a >= float(p.low), labels;
  const int n = cv::connectedComponents(above, labels, 8, CV_32S);
  std::vector<float> peak(size_t(n), 0.f);
  for (int y = 0; y < a.rows; ++y)
    for (int x = 0; x < a.cols; ++x) {
      const int l = labels.at<int32_t>(y, x);
      if (l > 0) peak[size_t(l)] = std::max(peak[size_t(l)], a.at<float>(y, x));
    }
  std::vector<float> level(size_t(n), 2.f);  // 2: above every attention, the region is dropped
  for (int l = 1; l < n; ++l)
    if (peak[size_t(l)] >= float(p.seed)) level[size_t(l)] = std::max(float(p.low), float(p.fraction) * peak[size_t(l)]);
  cv::Mat m(a.rows, a.cols, CV_32FC1);
  for (int y = 0; y < a.rows; ++y)
    for (int x = 0; x < a.cols; ++x) {
      const int l = labels.at<int32_t>(y, x);
      m.at<float>(y, x) = l > 0 && a.at<float>(y, x) >= level[size_t(l)] ? 1.f : 0.f;
    }
  return m;
}

}  // namespace

Image attention_to_mask(const Image& attention, const LedMaskOptions& o) {
  WGS_CHECK(o.rule && o.threshold && o.peak && o.dilate_iterations);  // resolved
  const int dilations = checked_dilations(*o.dilate_iterations);
  Image m(attention.width, attention.height, 1, ColorSpace::kLinear);
  if (*o.rule == LedThresholdRule::kPeak) {
    const cv::Mat a(attention.height, attention.width, CV_32FC1, const_cast<float*>(attention.data.data()));
    const cv::Mat on = peak_relative_mask(a, *o.peak);
    std::memcpy(m.data.data(), on.ptr<float>(), m.data.size() * sizeof(float));
  } else {
    for (size_t i = 0; i < m.data.size(); ++i) {
      const float a = attention.data[i];
      const bool on = *o.rule == LedThresholdRule::kBand ? (a >= o.band_lo && a <= o.band_hi) : a >= *o.threshold;
      m.data[i] = on ? 1.f : 0.f;
    }
  }
  if (dilations > 0) {
    cv::Mat mat(m.height, m.width, CV_32FC1, m.data.data());
    cv::dilate(mat, mat, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(3, 3)), cv::Point(-1, -1), dilations);
  }
  return m;
}

LedScore score_lens_masks(const std::string& name, const std::vector<Image>& predicted, const std::vector<Image>& truth) {
  if (truth.empty() || (predicted.size() != 1 && predicted.size() != truth.size()))
    throw InternalError("score_lens_masks: one prediction, or one per ground-truth mask");
  double inter = 0, uni = 0, pred = 0, gt = 0;
  for (size_t k = 0; k < truth.size(); ++k) {
    const Image& g = truth[k];
    const Image& m = predicted.size() == 1 ? predicted[0] : predicted[k];
    WGS_CHECK_EQ(m.data.size(), g.data.size());
    for (size_t i = 0; i < g.data.size(); ++i) {
      const bool p = m.data[i] > 0.5f, q = g.data[i] > 0.5f;
      inter += p && q, uni += p || q, pred += p, gt += q;
    }
  }
  const double n = double(truth.size() * truth[0].data.size());
  LedScore s;
  s.dataset = name;
  s.iou = uni > 0 ? inter / uni : 1.0;
  s.precision = pred > 0 ? inter / pred : (gt > 0 ? 0.0 : 1.0);
  s.recall = gt > 0 ? inter / gt : 1.0;
  s.gt_fraction = gt / n;
  s.mask_fraction = pred / n;
  return s;
}

namespace {

// The coverage-rule threshold of the dataset's resolved lens spec (generator.spec.effects.lens_droplets
// .mask_threshold), when it was generated with lens drops.
std::optional<double> coverage_rule_threshold(const Dataset& ds) {
  if (!ds.info.generator) return std::nullopt;
  const Json::json_pointer at("/spec/effects/lens_droplets/mask_threshold");
  if (!ds.info.generator->contains(at) || !ds.info.generator->at(at).is_number()) return std::nullopt;
  return ds.info.generator->at(at).get<double>();
}

// One view's lens coverage layer as a {0, 1} mask: coverage >= threshold (the generator's coverage rule).
Image coverage_mask(const std::string& path, double threshold, const Camera& c) {
  const Image cov = read_image(path);
  if (cov.width != c.width || cov.height != c.height)
    throw InputError(path, "expected a " + std::to_string(c.width) + "x" + std::to_string(c.height) + " coverage layer (the view's size), got " +
                               std::to_string(cov.width) + "x" + std::to_string(cov.height));
  Image m(cov.width, cov.height, 1);
  for (size_t i = 0; i < m.data.size(); ++i) m.data[i] = cov.data[i * size_t(cov.channels)] >= threshold ? 1.f : 0.f;
  return m;
}

Json score_json(const std::string& what, const LedScore& g, size_t views) {
  using namespace detect_key;
  return {{kScoreMasks, what}, {kScoreViews, views}, {kScoreIou, g.iou}, {kScorePrecision, g.precision},
          {kScoreRecall, g.recall}, {kGtFraction, g.gt_fraction}, {kMaskFraction, g.mask_fraction}};
}

// The network over `views` in chunks of `batch`, results in view order. The chunks run in parallel,
// each on one libtorch thread (LensDetector::attention): a chunk's maps do not depend on which thread
// ran it, so the output does not depend on the thread count (test restoration/lens_detector), and
// on 2 cores a dataset takes about half the time of one view after the other.
std::vector<Image> attention_in_batches(const LensDetector& led, const std::vector<Image>& views, const std::string& where,
                                        int batch, ProgressBar* bar) {
  const int64_t n = int64_t(views.size());
  std::vector<Image> out(views.size());
  parallel_for_chunks(0, n, batch, [&](int64_t, int64_t lo, int64_t hi) {
    const std::vector<Image> chunk(views.begin() + lo, views.begin() + hi);
    std::vector<Image> maps = led.attention(chunk, where);
    for (int64_t i = lo; i < hi; ++i) out[size_t(i)] = std::move(maps[size_t(i - lo)]);
    if (bar) bar->tick(hi - lo);
  });
  return out;
}

// The views per network call: a view-pooling network sees all views of the dataset in one call
// (one view at a time in per-view mode, where drops may slide), any other `batch`.
int pooled_batch(const LensDetector& led, int batch, size_t views, bool per_view) {
  if (led.architecture().view_pooling == LedViewPooling::kNone) return batch;
  return per_view ? 1 : int(std::max<size_t>(1, views));
}

// Pixel-wise mean, summed in view order (a fixed summation order).
Image average(const std::vector<Image>& maps) {
  Image sum(maps[0].width, maps[0].height, 1, ColorSpace::kLinear);
  for (const Image& a : maps)
    for (size_t i = 0; i < sum.data.size(); ++i) sum.data[i] += a.data[i];
  for (float& v : sum.data) v /= float(maps.size());
  return sum;
}

}  // namespace

Image mean_attention(const LensDetector& led, const std::vector<Image>& views, const std::string& where, int batch) {
  if (views.empty()) throw InputError(where, "no views to average");
  return average(attention_in_batches(led, views, where, pooled_batch(led, batch, views.size(), false), nullptr));
}

Json detect_settings_json(const std::string& weights_sha256, const DetectDatasetOptions& o, const LedMaskOptions& m) {
  WGS_CHECK(m.rule && m.threshold && m.peak && m.dilate_iterations);  // resolved options only
  using namespace detect_key;
  return Json{{kWeightsSha256, weights_sha256},
              {kImages, o.images_dir.empty() ? std::string(layout::kImagesDir) : fs::absolute(o.images_dir).lexically_normal().string()},
              {kAveraging, to_string(o.averaging)},
              {kRule, to_string(*m.rule)},
              {kThreshold, *m.rule == LedThresholdRule::kAbove ? Json(*m.threshold) : Json()},
              {kBand, *m.rule == LedThresholdRule::kBand ? Json{m.band_lo, m.band_hi} : Json()},
              {kPeakRule, *m.rule == LedThresholdRule::kPeak ? m.peak->to_json() : Json()},
              {kDilateIterations, *m.dilate_iterations}};
}

void use_adapted_peak_rule(LensDetector& led) {
  if (led.adapted_peak_rule()) led.set_peak_rule(led.adapted_peak_rule());
}

StageOutput detect_output(const std::string& out, const DetectDatasetOptions& options, const Json& adaptation) {
  StageOutput s;
  s.record = (fs::path(out) / kDetectReportFile).string();
  if (!fs::exists(s.record)) return s;
  const Json report = read_json_file(s.record);
  const bool adapted = !report.value(detect_key::kAdaptation, Json()).is_null(), asked = !adaptation.is_null();
  if (adapted != asked) {
    s.why = std::string("made ") + (adapted ? "with" : "without") + " adapting the LED to the dataset, asked for " +
            (adapted ? "without" : "with") + " it";
  } else {
    LensDetector led = LensDetector::load(options.weights);
    if (asked) use_adapted_peak_rule(led);
    s.why = settings_mismatch(report, detect_settings_json(led.metadata().value("weights_sha256", ""), options,
                                                           options.mask.resolved(led)));
    if (s.why.empty() && asked) s.why = settings_mismatch(report.at(detect_key::kAdaptation), adaptation);
  }
  s.state = s.why.empty() ? StageOutput::State::kComplete : StageOutput::State::kStale;
  return s;
}

DetectDatasetReport detect_dataset(const std::string& dataset, const std::string& out, const DetectDatasetOptions& o) {
  o.mask.validate();
  if (o.batch < 1 || o.batch > 64) throw InputError("detect batch", "expected 1..64, got " + std::to_string(o.batch));
  const auto start = std::chrono::steady_clock::now();
  const Dataset ds = read_dataset(dataset);
  LensDetector led = LensDetector::load(o.weights);
  if (o.adapt && o.averaging != LedAveraging::kTrainViews)
    throw InputError("detect --adapt", "adapts to drops fixed to the lens: it needs the train-views averaging, not --per-view");
  auto input_path = [&](const std::string& view) {
    return o.images_dir.empty() ? ds.path(ImageKind::kImages, view) : (fs::path(o.images_dir) / (view + layout::kImageExt)).string();
  };
  for (const Camera& c : ds.cameras)
    if (!fs::exists(input_path(c.name))) throw InputError(input_path(c.name), "missing: view " + c.name);
  std::set<std::string> train;
  if (o.averaging == LedAveraging::kTrainViews) {
    const auto& names = ds.split("train");
    train.insert(names.begin(), names.end());
    if (train.empty()) throw InputError(ds.root, "has an empty train split: nothing to average the LED attention over");
  }
  // The output folder before the network runs: a bad --out fails at once, not after every view.
  AtomicDirectory dir(out);
  // Attention of every view (per-view mode) or of the training views only (never the test views).
  std::vector<std::string> names;
  std::vector<Image> images;
  for (const Camera& c : ds.cameras) {
    if (o.averaging == LedAveraging::kTrainViews && !train.count(c.name)) continue;
    Image img = read_image(input_path(c.name));
    if (img.width != c.width || img.height != c.height)
      throw InputError(input_path(c.name), "is " + img.to_string() + ", cameras.json says " + std::to_string(c.width) + "x" + std::to_string(c.height));
    names.push_back(c.name);
    images.push_back(std::move(img));
  }
  Json adaptation;
  if (o.adapt) led = o.adapt(led, ds, names, images, adaptation);
  // After adapting, which may bring its own rule (the overrides were validated above, the weights' own
  // values when they were loaded).
  const LedMaskOptions mask_options = o.mask.resolved(led);
  const auto net_start = std::chrono::steady_clock::now();
  std::vector<Image> attention;
  {
    ProgressBar bar("detect lens drops", int64_t(images.size()));
    attention = attention_in_batches(led, images, ds.root,
                                     pooled_batch(led, o.batch, images.size(), o.averaging == LedAveraging::kPerView), &bar);
  }
  DetectDatasetReport report;
  report.mask = mask_options;
  report.seconds_per_view = seconds_since(net_start) / double(std::max<size_t>(1, images.size()));
  const Image averaged = o.averaging == LedAveraging::kTrainViews ? average(attention) : Image();
  if (o.save_attention) fs::create_directories(fs::path(dir.path()) / kDetectAttentionDir);
  Json views = Json::array();
  std::vector<Image> scored_masks, scored_truth;  // ground truth: the averaged (or every) view
  std::vector<Image> coverage_masks, coverage_truth;  // the same against the lens coverage
  const std::optional<double> coverage_threshold = coverage_rule_threshold(ds);
  const std::set<std::string> averaged_set(names.begin(), names.end());
  size_t k = 0;
  for (const Camera& c : ds.cameras) {
    const bool own = o.averaging == LedAveraging::kPerView;
    const Image& a = own ? attention[k] : averaged;
    if (own) ++k;
    if (a.width != c.width || a.height != c.height)
      throw InputError(input_path(c.name), "differs in size from the training views; kTrainViews averaging needs one size");
    const Image mask = attention_to_mask(a, mask_options);
    double frac = 0, mean = 0;
    for (size_t i = 0; i < mask.data.size(); ++i) frac += mask.data[i], mean += a.data[i];
    DetectViewReport v{c.name, frac / double(mask.data.size()), mean / double(mask.data.size())};
    write_mask((fs::path(dir.path()) / (c.name + layout::kImageExt)).string(), mask);
    if (o.save_attention) {
      Image soft = a;
      soft.space = ColorSpace::kSRGB;  // written as is: the PNG value is the attention
      write_image((fs::path(dir.path()) / kDetectAttentionDir / (c.name + layout::kImageExt)).string(), soft,
                  {PixelFormat::kUInt16, {}});
    }
    if (ds.has(ImageKind::kLensMask) && averaged_set.count(c.name) && fs::exists(ds.path(ImageKind::kLensMask, c.name))) {
      scored_truth.push_back(read_mask(ds.path(ImageKind::kLensMask, c.name)));
      scored_masks.push_back(mask);
    }
    const std::string coverage_path = ds.layer_path(layout::kLensCoverageLayer, c.name);
    if (coverage_threshold && averaged_set.count(c.name) && fs::exists(coverage_path)) {
      coverage_truth.push_back(coverage_mask(coverage_path, *coverage_threshold, c));
      coverage_masks.push_back(mask);
    }
    views.push_back({{detect_key::kView, v.view}, {detect_key::kMaskFraction, v.mask_fraction},
                     {detect_key::kMeanAttention, v.mean_attention}});
    report.views.push_back(v);
  }
  Json gt_json;
  if (!scored_truth.empty() && scored_truth.size() == averaged_set.size()) {
    report.ground_truth = score_lens_masks(ds.info.name, scored_masks, scored_truth);
    gt_json = score_json(layout::kLensMaskDir, *report.ground_truth, scored_truth.size());
  }
  Json coverage_json;
  if (!coverage_truth.empty() && coverage_truth.size() == averaged_set.size()) {
    report.coverage_truth = score_lens_masks(ds.info.name, coverage_masks, coverage_truth);
    report.coverage_threshold = *coverage_threshold;
    coverage_json = score_json(std::string(layout::kLayersDir) + "/" + layout::kLensCoverageLayer, *report.coverage_truth,
                               coverage_truth.size());
    coverage_json[detect_key::kThreshold] = *coverage_threshold;
  }
  report.seconds = seconds_since(start);
  using namespace detect_key;
  Json j{{kFormat, kDetectFormat},
         {kVersion, 1},
         {kDataset, fs::absolute(dataset).lexically_normal().string()},
         {kWeights, fs::absolute(o.weights + ".json").lexically_normal().string()},
         {kAdaptation, adaptation},
         {kAveragedViews, o.averaging == LedAveraging::kTrainViews ? Json(names) : Json()},
         {kAttention, o.save_attention ? Json(kDetectAttentionDir) : Json()},
         {kGroundTruth, gt_json},
         {kGroundTruthCoverage, coverage_json},
         {kSeconds, report.seconds},
         {kSecondsPerView, report.seconds_per_view},
         {kViews, views}};
  j.update(detect_settings_json(led.metadata().value("weights_sha256", ""), o, mask_options));
  write_file_atomic((fs::path(dir.path()) / kDetectReportFile).string(), j.dump(2) + "\n");
  dir.commit();
  return report;
}

DetectRecord read_detect_record(const std::string& out) {
  using namespace detect_key;
  const JsonReader r = JsonReader::from_file((fs::path(out) / kDetectReportFile).string());
  if (r.get<std::string>(kFormat) != kDetectFormat) throw InputError(r.where(kFormat), std::string("expected ") + kDetectFormat);
  DetectRecord rec;
  rec.seconds = r.get<double>(kSeconds);
  rec.weights_sha256 = r.get<std::string>(kWeightsSha256);
  if (r.has(kGroundTruth) && !r.value()[kGroundTruth].is_null()) {
    const JsonReader g = r.child(kGroundTruth);
    LedScore score;
    score.iou = g.get<double>(kScoreIou);
    score.precision = g.get<double>(kScorePrecision);
    score.recall = g.get<double>(kScoreRecall);
    score.gt_fraction = g.get<double>(kGtFraction);
    score.mask_fraction = g.get<double>(kMaskFraction);
    rec.ground_truth = score;
  }
  return rec;
}

std::string silent_led_warning(const DetectRecord& record) {
  if (!record.ground_truth) return "";
  const double truth = record.ground_truth->gt_fraction, masked = record.ground_truth->mask_fraction;
  if (truth < kSilentLedTruthFraction || masked >= kSilentLedMaskShare * truth) return "";
  char s[256];
  std::snprintf(s, sizeof s,
                "the LED masked %.4f%% of the pixels where the ground-truth lens drops cover %.1f%%: its masks "
                "exclude almost none of the drops (other optics or drop sizes than it was calibrated on? try "
                "detect --adapt)",
                100 * masked, 100 * truth);
  return s;
}

}  // namespace weathergs::restoration::led
