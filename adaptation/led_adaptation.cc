#include "adaptation/led_adaptation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/parallel.h"
#include "core/progress.h"  // ProgressBar, seconds_since
#include "generator/lens/drops.h"
#include "generator/lens/lens_render.h"
#include "generator/weather.h"
#include "generator/weather_spec.h"
#include "restoration/led/detect_dataset.h"

namespace weathergs::adaptation {
namespace {

constexpr double kMaxPasses = 1000;

// Where the base network's averaged map may hide the scene's own drops: m >= level, dilated with a
// 3x3 cross `dilations` times. 1 = left out of the loss.
Image ignore_region(const Image& averaged, double level, int dilations) {
  cv::Mat m(averaged.height, averaged.width, CV_8UC1);
  for (int y = 0; y < averaged.height; ++y)
    for (int x = 0; x < averaged.width; ++x) m.at<uint8_t>(y, x) = averaged.at(x, y) >= float(level) ? 1 : 0;
  if (dilations > 0)
    cv::dilate(m, m, cv::getStructuringElement(cv::MORPH_CROSS, cv::Size(3, 3)), cv::Point(-1, -1), dilations,
               cv::BORDER_CONSTANT, cv::Scalar(0));
  Image out(averaged.width, averaged.height, 1, ColorSpace::kLinear);
  for (int y = 0; y < averaged.height; ++y)
    for (int x = 0; x < averaged.width; ++x) out.data[size_t(y) * size_t(averaged.width) + size_t(x)] = m.at<uint8_t>(y, x);
  return out;
}

}  // namespace

void LedAdaptOptions::validate() const {
  if (layouts < 1 || layouts > kMaxAdaptLayouts)
    throw InputError("LED adaptation layouts", "expected 1.." + std::to_string(kMaxAdaptLayouts) + ", got " + std::to_string(layouts));
  if (!(passes > 0 && passes <= kMaxPasses))
    throw InputError("LED adaptation passes", "expected in (0, " + std::to_string(int(kMaxPasses)) + "], got " + std::to_string(passes));
  if (iterations && (*iterations < 1 || *iterations > kMaxAdaptIterations))
    throw InputError("LED adaptation iterations", "expected 1.." + std::to_string(kMaxAdaptIterations) + ", got " + std::to_string(*iterations));
  if (!(learning_rate > 0 && learning_rate < 1))
    throw InputError("LED adaptation learning rate", "expected in (0, 1), got " + std::to_string(learning_rate));
  if (batch < 1 || batch > 64) throw InputError("LED adaptation batch", "expected 1..64, got " + std::to_string(batch));
  if (!(ignore_level > 0 && ignore_level <= 1))
    throw InputError("LED adaptation ignore level", "expected in (0, 1], got " + std::to_string(ignore_level));
  if (ignore_dilations < 0 || ignore_dilations > 16)
    throw InputError("LED adaptation ignore dilations", "expected 0..16, got " + std::to_string(ignore_dilations));
  if (threads < 0) throw InputError("LED adaptation threads", "expected >= 0, got " + std::to_string(threads));
}

int LedAdaptOptions::fine_tune_iterations(size_t train_views) const {
  if (iterations) return *iterations;
  const double n = std::round(passes * double(layouts) * double(train_views) / double(batch));
  if (n > kMaxAdaptIterations)
    throw InputError("LED adaptation", std::to_string(train_views) + " training views at " + std::to_string(passes) +
                                           " passes need " + std::to_string(int64_t(n)) + " iterations, over the " +
                                           std::to_string(kMaxAdaptIterations) + " allowed: fix a count instead (detect --adapt-iterations)");
  return std::max(1, int(n));
}

Json adapt_layout_spec(int k) {
  const LedAdaptLayout& l = kAdaptLayouts[k % 4];
  return Json{{"seed", kAdaptSeedBase + uint64_t(k) + 1},
              {"style", l.style},
              {"effects",
               {{"lens_droplets",
                 {{"count", l.count},
                  {"radius_mm", {kAdaptRadiusMm[0], kAdaptRadiusMm[1]}},
                  {"glass_distance_m", kAdaptGlassDistanceM}}}}}};
}

restoration::led::LensDetector adapt_led(const restoration::led::LensDetector& base, const Dataset& ds,
                                    const std::vector<std::string>& views, const std::vector<Image>& images,
                                    const LedAdaptOptions& o, Json& report) {
  o.validate();
  if (views.empty() || views.size() != images.size())
    throw InputError(ds.root, "LED adaptation needs the training views and their images (got " + std::to_string(views.size()) +
                                  " names, " + std::to_string(images.size()) + " images)");
  const int iterations = o.fine_tune_iterations(views.size());  // before any work: it may refuse
  const auto start = std::chrono::steady_clock::now();
  std::vector<Image> rgb, linear;
  std::vector<Camera> cameras;
  for (size_t i = 0; i < views.size(); ++i) {
    rgb.push_back(to_rgb(images[i]));
    linear.push_back(to_linear(rgb.back()));
    cameras.push_back(ds.camera(views[i]));
    if (rgb.back().width != cameras.back().width || rgb.back().height != cameras.back().height)
      throw InputError(ds.root + ": view " + views[i], "image is " + rgb.back().to_string() + ", cameras.json says " +
                                                           std::to_string(cameras.back().width) + "x" + std::to_string(cameras.back().height));
  }

  // The scene's own drops are unlabelled: leave out where the base network may see them.
  const Image averaged = restoration::led::mean_attention(base, rgb, ds.root);
  const Image ignore = ignore_region(averaged, o.ignore_level, o.ignore_dilations);
  double ignored = 0;
  for (float v : ignore.data) ignored += v;
  ignored /= double(ignore.data.size());

  // The sky radiance as `weathergs weather` estimates it over these views (the physical style's
  // environment light of the drops).
  std::vector<std::array<double, 3>> sky_per_view(views.size());
  parallel_for(0, int64_t(views.size()), [&](int64_t i) { sky_per_view[size_t(i)] = generator::estimate_sky_radiance(linear[size_t(i)]); });
  const Eigen::Vector3f sky = generator::mean_sky_radiance(sky_per_view);

  // New drops over every view, layout after layout; the example order is layout-major, view order.
  std::vector<restoration::led::LedExample> examples(size_t(o.layouts) * views.size());
  Json layouts = Json::array();
  {
    ProgressBar bar("LED adaptation: drops", int64_t(examples.size()));
    for (int k = 0; k < o.layouts; ++k) {
      const Json spec_json = adapt_layout_spec(k);
      const generator::WeatherSpec spec = generator::parse_weather_spec(JsonReader(spec_json, "LED adaptation layout " + std::to_string(k)));
      WGS_CHECK(spec.lens_droplets.has_value());
      std::vector<Camera> applied;
      for (const Camera& c : cameras) applied.push_back(spec.camera.apply(c));
      const generator::lens::LensDropletSpec resolved = generator::lens::resolve_lens_droplet_spec(*spec.lens_droplets, applied.front());
      const generator::lens::LensDropletRenderer renderer(resolved, spec.seed, applied.front());
      std::vector<double> drop_fraction(views.size(), 0.0);
      parallel_for(0, int64_t(views.size()), [&](int64_t i) {
        const Camera& cam = applied[size_t(i)];
        generator::lens::LensViewResult r = renderer.render(linear[size_t(i)], cam, cam.time_s, &sky);
        require_finite(r.image, "internal: LED adaptation view '" + views[size_t(i)] + "'");
        restoration::led::LedExample& e = examples[size_t(k) * views.size() + size_t(i)];
        e.image = quantize_uint8(to_srgb(r.image));  // what the view would be as a PNG
        e.mask = std::move(r.mask);
        e.group = k;
        e.weight = Image(e.image.width, e.image.height, 1, ColorSpace::kLinear);
        double f = 0;
        for (size_t p = 0; p < e.weight.data.size(); ++p) {
          const bool drop = e.mask.data[p] > 0.5f;
          e.weight.data[p] = std::max(drop ? 1.f : 0.f, 1.f - ignore.data[p]);
          f += drop;
        }
        drop_fraction[size_t(i)] = f / double(e.mask.data.size());
        if (o.progress) bar.tick();
      });
      double mean_fraction = 0;
      for (double f : drop_fraction) mean_fraction += f;
      layouts.push_back({{"spec", spec_json}, {"drop_fraction", mean_fraction / double(views.size())}});
    }
  }

  restoration::led::LensDetector adapted = base.clone();
  restoration::led::LedTrainOptions t;
  t.arch = base.architecture();
  t.iterations = iterations;
  t.batch = o.batch;
  t.learning_rate = o.learning_rate;
  t.seed = o.seed;
  t.threads = o.threads;
  t.gradient = kAdaptGradient;
  t.progress = o.progress;
  const restoration::led::LedTrainRecord rec = adapted.train(examples, t);
  restoration::led::use_adapted_peak_rule(adapted);
  report = Json{{"method", "fine-tune on the training views with new lens drops (docs/restoration_led.md, \"Adapted to the scene\")"},
                {"views", views},
                {"layouts", layouts},
                {"threads", o.threads > 0 ? o.threads : num_threads()},
                {"ignored_fraction", ignored},
                {"loss_first_50", rec.loss_curve.empty() ? 0.0 : rec.loss_curve.front()},
                {"loss_last_50", rec.loss_curve.empty() ? 0.0 : rec.loss_curve.back()},
                {"training_seconds", rec.seconds},
                {"peak_rule", base.adapted_peak_rule() ? "adapted_peak_rule" : "peak_rule"},
                {"seconds", seconds_since(start)}};
  report["passes"] = o.iterations ? Json() : Json(o.passes);  // null: the count was fixed
  report.update(adaptation_settings_json(o, views.size()));
  return adapted;
}

Json adaptation_settings_json(const LedAdaptOptions& o, size_t train_views) {
  return Json{{"layout_count", o.layouts},
              {"iterations", o.fine_tune_iterations(train_views)},
              {"batch", o.batch},
              {"learning_rate", o.learning_rate},
              {"seed", o.seed},
              {"ignore_level", o.ignore_level},
              {"ignore_dilations", o.ignore_dilations},
              {"gradient", restoration::led::to_string(kAdaptGradient)}};
}

restoration::led::LedAdaptation led_adaptation_hook(const LedAdaptOptions& options) {
  return [options](const restoration::led::LensDetector& base, const Dataset& dataset, const std::vector<std::string>& views,
                   const std::vector<Image>& images, Json& report) { return adapt_led(base, dataset, views, images, options, report); };
}

}  // namespace weathergs::adaptation
