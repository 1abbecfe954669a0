#include "restoration/aef/aef_training.h"

#include <cmath>
#include <filesystem>
#include <set>

#include "core/error.h"
#include "core/json_reader.h"

namespace weathergs::restoration::aef {

namespace fs = std::filesystem;

namespace {

std::string dataset_name(const std::string& dir) { return fs::path(dir).lexically_normal().filename().string(); }

Image read_view(const std::string& path, const Camera& c, int channels) {
  if (!fs::exists(path)) throw InputError(path, "missing: view " + c.name);
  Image img = channels == 1 ? read_mask(path) : to_rgb(read_image(path));
  if (img.width != c.width || img.height != c.height) throw InputError(path, "is " + img.to_string() + ", expected the view's size");
  return img;
}

double psnr(const Image& a, const Image& b) {
  WGS_CHECK(a.same_shape(b));
  double se = 0;
  for (size_t i = 0; i < a.data.size(); ++i) {
    const double d = double(std::clamp(a.data[i], 0.f, 1.f)) - std::clamp(b.data[i], 0.f, 1.f);
    se += d * d;
  }
  const double mse = se / double(a.data.size());
  return mse > 0 ? 10 * std::log10(1 / mse) : 100.0;
}

// Before minutes of training: the folder of the weights must exist.
void check_out_stem(const std::string& stem) {
  const fs::path dir = fs::absolute(stem).parent_path();
  if (!fs::is_directory(dir)) throw InputError(stem, "its folder " + dir.string() + " does not exist");
}

void check_disjoint(const std::vector<std::string>& train, const std::vector<std::string>& held_out) {
  const std::set<std::string> train_set(train.begin(), train.end());
  for (const std::string& h : held_out)
    if (train_set.count(h)) throw InputError(h, "is both a training and a held-out dataset");
}

Json names_of(const std::vector<std::string>& dirs) {
  Json names = Json::array();
  for (const std::string& d : dirs) names.push_back(dataset_name(d));
  return names;
}

}  // namespace

WeatherClass weather_class_of(const Dataset& ds) {
  const std::string& w = ds.info.weather;
  const bool rain = w.find("rain") != std::string::npos, snow = w.find("snow") != std::string::npos;
  if (rain && snow) throw InputError(ds.file(layout::kDatasetJson), "weather \"" + w + "\" has both rain and snow: no single AEF class");
  return rain ? WeatherClass::kRain : snow ? WeatherClass::kSnow : WeatherClass::kNone;
}

WeatherClass selector_class_of(const Dataset& ds) {
  const WeatherClass c = weather_class_of(ds);
  if (c == WeatherClass::kNone || !ds.has(ImageKind::kTargetNoParticles)) return c;
  double sum = 0;
  for (const Camera& cam : ds.cameras)
    sum += psnr(read_view(ds.path(ImageKind::kImages, cam.name), cam, 3), read_view(ds.path(ImageKind::kTargetNoParticles, cam.name), cam, 3));
  return ds.cameras.empty() || sum / double(ds.cameras.size()) > kInvisibleParticlesPsnrDb ? WeatherClass::kNone : c;
}

WeatherClass class_of(AefPluginKind kind) { return kind == AefPluginKind::kDerain ? WeatherClass::kRain : WeatherClass::kSnow; }

std::vector<AefExample> read_aef_examples(const std::string& dataset) {
  const Dataset ds = read_dataset(dataset);
  const bool particles = weather_class_of(ds) != WeatherClass::kNone;
  if (particles && !ds.has(ImageKind::kTargetNoParticles))
    throw InputError(ds.dir(ImageKind::kTargetNoParticles), "missing: a weathered training dataset needs the generator's targets (--targets)");
  std::vector<AefExample> out;
  for (const Camera& c : ds.cameras) {
    AefExample e;
    e.image = read_view(ds.path(ImageKind::kImages, c.name), c, 3);
    e.target = particles ? read_view(ds.path(ImageKind::kTargetNoParticles, c.name), c, 3) : e.image;
    e.alpha = particles && ds.has(ImageKind::kParticleMask) ? read_view(ds.path(ImageKind::kParticleMask, c.name), c, 1)
                                                            : Image(c.width, c.height, 1, ColorSpace::kLinear);
    out.push_back(std::move(e));
  }
  return out;
}

std::vector<AefHeldOutScore> score_aef(const AefPlugin& plugin, const std::vector<std::string>& datasets) {
  std::vector<AefHeldOutScore> scores;
  for (const std::string& d : datasets) {
    AefHeldOutScore s;
    s.dataset = dataset_name(d);
    for (const AefExample& e : read_aef_examples(d)) {
      s.psnr_input += psnr(e.image, e.target);
      s.psnr_restored += psnr(plugin.restore(e.image, d).restored, e.target);
      ++s.views;
    }
    if (s.views > 0) s.psnr_input /= s.views, s.psnr_restored /= s.views;
    scores.push_back(s);
  }
  return scores;
}

TrainAefResult train_aef(AefPluginKind kind, const std::vector<std::string>& train_datasets, const std::vector<std::string>& held_out,
                         const std::string& out_stem, const TrainAefOptions& o) {
  o.train.validate();
  if (train_datasets.empty()) throw InputError("train-aef", "no training datasets given");
  check_out_stem(out_stem);
  check_disjoint(train_datasets, held_out);
  const WeatherClass wanted = class_of(kind);
  auto relevant = [&](const std::string& d) {
    const WeatherClass c = weather_class_of(read_dataset(d));
    return c == wanted || c == WeatherClass::kNone;
  };
  TrainAefResult result;
  std::vector<AefExample> examples;
  std::vector<std::string> used, held;
  for (const std::string& d : train_datasets)
    if (relevant(d)) {
      used.push_back(d);
      for (AefExample& e : read_aef_examples(d)) examples.push_back(std::move(e));
    }
  for (const std::string& d : held_out)
    if (relevant(d)) held.push_back(d);
  if (examples.empty()) throw InputError("train-aef", std::string("none of the training datasets has ") + to_string(wanted) + " or clear views");
  result.examples = examples.size();
  AefPlugin plugin(kind, o.train.arch, o.train.seed);
  result.record = plugin.train(examples, o.train);
  examples.clear();
  result.held_out = score_aef(plugin, held);
  Json scores = Json::array();
  for (const AefHeldOutScore& s : result.held_out)
    scores.push_back({{"dataset", s.dataset}, {"views", s.views}, {"psnr_input_db", s.psnr_input}, {"psnr_restored_db", s.psnr_restored}});
  const AefTrainOptions& t = o.train;
  const Json extra{{"model", std::string("learned Atmospheric Effect Filter plugin (residual encoder-decoder): ") + to_string(kind)},
                   {"command", o.command},
                   {"training",
                    {{"datasets", names_of(used)},
                     {"examples", result.examples},
                     {"iterations", t.iterations},
                     {"batch", t.batch},
                     {"crop", t.crop},
                     {"learning_rate", t.learning_rate},
                     {"ssim_weight", t.ssim_weight},
                     {"alpha_weight", t.alpha_weight},
                     {"seed", t.seed},
                     {"threads", t.threads},
                     {"seconds", result.record.seconds},
                     {"loss_per_50_iterations", result.record.loss_curve}}},
                   {"held_out", {{"datasets", names_of(held)}, {"scores", scores}}}};
  plugin.save(out_stem, extra);
  return result;
}

SelectorCalibration calibrate_selector(const WeatherSelector& selector, const std::vector<std::string>& held_out) {
  if (held_out.empty()) throw InputError("selector calibration", "needs at least one held-out dataset");
  struct Cached {
    std::string name;
    WeatherClass label;
    std::vector<std::vector<float>> embeddings;
  };
  std::vector<Cached> cache;
  for (const std::string& d : held_out) {
    const Dataset ds = read_dataset(d);
    Cached c{dataset_name(d), selector_class_of(ds), {}};
    for (const Camera& cam : ds.cameras) c.embeddings.push_back(selector.embed(read_view(ds.path(ImageKind::kImages, cam.name), cam, 3), d));
    cache.push_back(std::move(c));
  }
  auto view_accuracy = [&](double theta) {
    int right = 0, n = 0;
    for (const Cached& c : cache)
      for (const auto& e : c.embeddings) right += selector.select(e, theta).choice == c.label, ++n;
    return n > 0 ? double(right) / n : 0.0;
  };
  // The best accuracy is usually reached on a run of thetas; its middle is the most robust choice.
  std::vector<double> acc;
  for (int k = 0; k <= 200; ++k) acc.push_back(view_accuracy(-1 + 0.01 * k));
  const double best = *std::max_element(acc.begin(), acc.end());
  int run_start = -1, best_start = 0, best_len = 0;
  for (int k = 0; k <= 201; ++k) {
    const bool on = k <= 200 && acc[size_t(k)] >= best - 1e-12;
    if (on && run_start < 0) run_start = k;
    if (!on && run_start >= 0) {
      if (k - run_start > best_len) best_len = k - run_start, best_start = run_start;
      run_start = -1;
    }
  }
  SelectorCalibration cal;
  cal.theta = -1 + 0.01 * (best_start + (best_len - 1) / 2.0);
  cal.view_accuracy = view_accuracy(cal.theta);
  int scenes_right = 0;
  for (const Cached& c : cache) {
    int right = 0;
    for (const auto& e : c.embeddings) right += selector.select(e, cal.theta).choice == c.label;
    const Selection scene = selector.select(WeatherSelector::mean_embedding(c.embeddings), cal.theta);
    scenes_right += scene.choice == c.label;
    cal.views += int(c.embeddings.size());
    cal.per_dataset.push_back({{"dataset", c.name},
                               {"label", to_string(c.label)},
                               {"views", c.embeddings.size()},
                               {"views_right", right},
                               {"scene_choice", to_string(scene.choice)}});
  }
  cal.scenes = int(cache.size());
  cal.scene_accuracy = double(scenes_right) / double(cache.size());
  return cal;
}

TrainSelectorResult train_selector(const std::vector<std::string>& train_datasets, const std::vector<std::string>& held_out,
                                   const std::string& out_stem, const TrainSelectorOptions& o) {
  o.train.validate();
  if (train_datasets.empty()) throw InputError("train-aef", "no training datasets given");
  check_out_stem(out_stem);
  check_disjoint(train_datasets, held_out);
  std::vector<SelectorExample> examples;
  for (const std::string& d : train_datasets) {
    const Dataset ds = read_dataset(d);
    const WeatherClass label = selector_class_of(ds);
    for (const Camera& c : ds.cameras) examples.push_back({read_view(ds.path(ImageKind::kImages, c.name), c, 3), label});
  }
  TrainSelectorResult result;
  result.examples = examples.size();
  WeatherSelector selector(o.train.arch, o.train.seed);
  result.record = selector.train(examples, o.train);
  examples.clear();
  if (!held_out.empty()) {
    result.calibration = calibrate_selector(selector, held_out);
    selector.set_theta(result.calibration.theta);
  }
  const SelectorTrainOptions& t = o.train;
  const SelectorCalibration& cal = result.calibration;
  const Json extra{{"model", "weather selector (tiny CNN embedder + instruction prototypes, cosine vs theta)"},
                   {"command", o.command},
                   {"training",
                    {{"datasets", names_of(train_datasets)},
                     {"examples", result.examples},
                     {"iterations", t.iterations},
                     {"batch", t.batch},
                     {"learning_rate", t.learning_rate},
                     {"scale", t.scale},
                     {"seed", t.seed},
                     {"threads", t.threads},
                     {"seconds", result.record.seconds},
                     {"loss_per_50_iterations", result.record.loss_curve}}},
                   {"calibration",
                    {{"held_out", names_of(held_out)},
                     {"grid", "theta -1..1 step 0.01, maximizing the per-view accuracy over the held-out views"},
                     {"labels", "dataset.json weather; none where the particles are invisible (input vs no-particle target above " +
                                    std::to_string(int(kInvisibleParticlesPsnrDb)) + " dB)"},
                     {"theta", cal.theta},
                     {"view_accuracy", cal.view_accuracy},
                     {"views", cal.views},
                     {"scene_accuracy", cal.scene_accuracy},
                     {"scenes", cal.scenes},
                     {"per_dataset", cal.per_dataset}}}};
  selector.save(out_stem, extra);
  return result;
}

}  // namespace weathergs::restoration::aef
