// Path-tracer validation of the weather compositor: capture/cycles_validation.h does the work.
//
//   bench_capture_cycles_validation --dataset DIR [--view 001] [--samples 256] [--coverage-samples 8xS] [--nearest 20] [--out DIR]
//                                   [--blender blender] [--reuse-renders] [--glass-mm 1] [--glass-ior 1.52] [--no-camera-body]
//                                   [--reference-dataset DIR]
#include <cstdio>
#include <string>

#include "core/error.h"
#include "capture/cycles_validation.h"

using namespace weathergs;

int main(int argc, char** argv) {
  try {
    capture::CyclesValidationOptions o;
    o.blender_script = std::string(WEATHERGS_SOURCE_DIR) + "/blender_scripts/render_scene.py";
    for (int i = 1; i < argc; ++i) {
      const std::string k = argv[i];
      auto next = [&]() -> std::string {
        if (i + 1 >= argc) throw InputError(k, "expected a value");
        return argv[++i];
      };
      if (k == "--dataset") o.dataset = next();
      else if (k == "--view") o.view = next();
      else if (k == "--out") o.out_dir = next();
      else if (k == "--samples") o.samples = std::stoi(next());
      else if (k == "--nearest") o.nearest = std::stoi(next());
      else if (k == "--coverage-samples") o.coverage_samples = std::stoi(next());
      else if (k == "--blender") o.blender = next();
      else if (k == "--reuse-renders") o.reuse_renders = true;
      else if (k == "--glass-mm") o.glass_thickness_m = 1e-3 * std::stod(next());
      else if (k == "--glass-ior") o.glass_refractive_index = std::stod(next());
      else if (k == "--reference-dataset") o.reference_dataset = next();
      else if (k == "--no-camera-body") o.camera_body = false;
      else throw InputError(k, "unknown option (expected --dataset, --view, --samples, --coverage-samples, --nearest, --out, --blender, "
                               "--reuse-renders, --glass-mm, --glass-ior, --no-camera-body, --reference-dataset)");
    }
    Json result = capture::validate_against_cycles(o);
    if (result.contains("streaks")) result.erase("streaks");
    std::printf("%s\n", result.dump(1).c_str());
    return 0;
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
}
