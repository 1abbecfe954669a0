#include "generator/lens/lens_stage.h"

#include "core/dataset_layout.h"

namespace weathergs::generator::lens {

void LensDropletStage::run(WeatherView& view) const {
  LensViewResult r = renderer_.render(view.radiance, view.camera, view.camera.time_s, &view.environment.sky);
  view.radiance = std::move(r.image);
  view.layers[layout::kLensCoverageLayer] = std::move(r.coverage);
  view.lens_mask = std::move(r.mask);
  view.lens_drops = std::move(r.drops);
  view.counters["lens_camera_rays"] += r.camera_rays;
  view.counters["lens_water_rays"] += r.water_rays;
  view.counters["lens_embree_rays"] += r.embree_rays;
}

}  // namespace weathergs::generator::lens
