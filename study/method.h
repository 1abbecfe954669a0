// The reconstruction methods of the study, one recipe each (docs/study.md). A recipe says what a
// method trains on: which images, which loss masks, which SfM points. Methods that need the
// restoration part (the AEF and LED of WeatherGS) join here when restoration/ exists.
#pragma once

#include <string>
#include <vector>

#include "reconstruction/run.h"

namespace weathergs::study {

enum class Method {
  k3dgs,     // vanilla 3DGS on the weathered images (the paper's baseline)
  kOracle,   // 3DGS on the clean images and their SfM points: the upper bound
  kGtMasks,  // 3DGS on the weathered images with the generator's particle and lens masks excluded
  kAefTophat,  // the classical AEF (restoration/particle_filter.h) on every view, then 3DGS on the
               // filtered images: WeatherGS's first stage without learned weights and without the LED
};
const char* to_string(Method m);
std::vector<Method> all_methods();
// InputError naming `where` and the known names.
Method parse_method(const std::string& name, const std::string& where);
std::string method_description(Method m);

struct Recipe {
  recon::TrainImages images = recon::TrainImages::kImages;
  recon::TrainMasks masks = recon::TrainMasks::kNone;
  bool clean_points = false;  // initialize from sparse_clean/0 (clean/ triangulated) instead of sparse/0
  bool particle_filter = false;  // train on the classical AEF's restored images (RUN/filtered/)
};
Recipe recipe(Method m);

}  // namespace weathergs::study
