#include "study/method.h"

#include "core/error.h"

namespace weathergs::study {

const char* to_string(Method m) {
  switch (m) {
    case Method::k3dgs: return "3dgs";
    case Method::kOracle: return "oracle";
    case Method::kGtMasks: return "gt-masks";
    case Method::kAefTophat: return "aef-tophat";
    case Method::kWeatherGS: return "weathergs";
    case Method::kWeatherGSNoAef: return "weathergs-no-aef";
    case Method::kWeatherGSNoLed: return "weathergs-no-led";
    case Method::kRobust3dgs: return "robust-3dgs";
    case Method::kDesplat: return "desplat";
    case Method::kGsWLite: return "gs-w-lite";
    case Method::kNerf: return "nerf";
    case Method::kDerainNerf: return "derainnerf";
    case Method::kWeatherGSNerf: return "weathergs-nerf";
    case Method::kNerfOracle: return "nerf-oracle";
  }
  WGS_CHECK(false);
  return "";
}

std::vector<Method> all_methods() {
  return {Method::k3dgs,     Method::kOracle,         Method::kGtMasks,       Method::kAefTophat,
          Method::kWeatherGS, Method::kWeatherGSNoAef, Method::kWeatherGSNoLed, Method::kRobust3dgs,
          Method::kDesplat,  Method::kGsWLite,        Method::kNerf,           Method::kDerainNerf,    Method::kWeatherGSNerf,
          Method::kNerfOracle};
}

Method parse_method(const std::string& name, const std::string& where) {
  std::string known;
  for (Method m : all_methods()) {
    if (name == to_string(m)) return m;
    known += (known.empty() ? "" : ", ") + std::string(to_string(m));
  }
  throw InputError(where, "unknown method \"" + name + "\" (known: " + known + ")");
}

std::string method_description(Method m) {
  switch (m) {
    case Method::k3dgs: return "vanilla 3DGS on the weathered images";
    case Method::kOracle: return "3DGS on the clean images and their SfM points (upper bound)";
    case Method::kGtMasks: return "3DGS on the weathered images, ground-truth particle and lens masks excluded from the loss";
    case Method::kAefTophat: return "classical particle filter (morphological top-hat) on every view, then 3DGS";
    case Method::kWeatherGS:
      return "WeatherGS: AEF (learned derain/desnow plugin chosen by the weather selector) on every view, LED on the "
             "raw views averaged over the training views, 3DGS on the filtered images with the LED mask excluded";
    case Method::kWeatherGSNoAef: return "WeatherGS without the AEF: LED on the raw views, masked 3DGS on the raw images";
    case Method::kWeatherGSNoLed: return "WeatherGS without the LED: AEF (learned, selector) on every view, then 3DGS";
    case Method::kRobust3dgs:
      return "3DGS with the RobustFilter distractor mask (SpotLessSplats' robust baseline: pixels above the running "
             "70th-percentile error excluded from the loss, annealed), no opacity reset";
    case Method::kDesplat:
      return "3DGS with DeSplat-style distractor Gaussians: " + std::to_string(kDesplatDistractorsPerView) +
             " per training view in front of its camera, rendered only for that view, dropped at test time";
    case Method::kGsWLite:
      return "GS-W-style 3DGS in the wild without a pretrained encoder: per-view affine appearance (identity at "
             "test time) and a learned per-view visibility map with GS-W's (1 - M)^2 regulariser";
    case Method::kNerf: return "grid radiance field (DVGO/Plenoxels family, docs/nerf.md) on the weathered images";
    case Method::kDerainNerf:
      return "DerainNeRF: LED attention per view (not averaged) as occlusion masks excluded from the radiance "
             "field's MSE";
    case Method::kWeatherGSNerf:
      return "Ours-NeRF: AEF (learned, selector) on every view, LED averaged over the training views, radiance "
             "field with the LED mask excluded";
    case Method::kNerfOracle: return "grid radiance field on the clean images (its upper bound)";
  }
  WGS_CHECK(false);
  return "";
}

Recipe recipe(Method m) {
  Recipe r;
  switch (m) {
    case Method::k3dgs: break;
    case Method::kOracle:
      r.images = recon::TrainImages::kClean;
      r.clean_points = true;
      break;
    case Method::kGtMasks: r.masks = recon::TrainMasks::kAll; break;
    case Method::kAefTophat:
      r.particle_filter = true;
      r.aef = restoration::FilterMethod::kTopHat;
      break;
    case Method::kWeatherGS: r.particle_filter = r.lens_detector = true; break;
    case Method::kWeatherGSNoAef: r.lens_detector = true; break;
    case Method::kWeatherGSNoLed: r.particle_filter = true; break;
    case Method::kRobust3dgs: r.robust = true; break;
    case Method::kDesplat: r.distractors_per_view = kDesplatDistractorsPerView; break;
    case Method::kGsWLite: r.in_the_wild = true; break;
    case Method::kNerf: r.backend = Backend::kNerf; break;
    case Method::kDerainNerf:
      r.backend = Backend::kNerf;
      r.lens_detector = r.led_per_view = true;
      break;
    case Method::kWeatherGSNerf:
      r.backend = Backend::kNerf;
      r.particle_filter = r.lens_detector = true;
      break;
    case Method::kNerfOracle:
      r.backend = Backend::kNerf;
      r.images = recon::TrainImages::kClean;
      r.clean_points = true;
      break;
  }
  return r;
}

}  // namespace weathergs::study
