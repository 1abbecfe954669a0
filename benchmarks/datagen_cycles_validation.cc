// Path-tracer validation of the weather compositor (issue 5, "Accuracy costs time").
//
//   bench_datagen_cycles_validation --dataset DIR --view 003 [--samples 256] [--out DIR]
//
// DIR is a dataset made by `weathergs generate` with the generator's particle manifests
// (layers/particles_<species>/<view>.csv). The view's particles (position at shutter open, velocity,
// visual diameter) go to Blender as water spheres (rain) or translucent white spheres (snow), moving
// linearly over the exposure; Cycles renders the variant's scene with and without them (same sampling
// seed, so the noise of paths that miss every particle cancels) and motion blur. The weather layers
// weathered - clean (linear RGB) of Cycles and of the C++ compositor are compared: PSNR of their
// difference, and, for scale, the PSNR of "no weather at all" against the Cycles layer.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/error.h"
#include "core/image.h"
#include "datagen/blender.h"
#include "datagen/process.h"

using namespace weathergs;
using namespace weathergs::datagen;
namespace fs = std::filesystem;

namespace {

struct Args {
  std::string dataset, view = "001", out = "cycles_validation", blender = "blender";
  int samples = 256;
};

Args parse(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw InputError(k, "expected a value");
      return argv[++i];
    };
    if (k == "--dataset") a.dataset = next();
    else if (k == "--view") a.view = next();
    else if (k == "--out") a.out = next();
    else if (k == "--samples") a.samples = std::stoi(next());
    else if (k == "--blender") a.blender = next();
    else throw InputError(k, "unknown option (expected --dataset, --view, --samples, --out, --blender)");
  }
  if (a.dataset.empty()) throw InputError("--dataset", "required");
  if (a.samples < 1) throw InputError("--samples", "expected >= 1");
  return a;
}

Json read_particles(const std::string& csv, const std::string& kind) {
  std::ifstream in(csv);
  if (!in) throw InputError(csv, "particle manifest not found (generate with manifests on)");
  std::string line;
  std::getline(in, line);  // header: id,diameter_mm,visual_diameter_mm,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,camera_z_m,visible
  Json items = Json::array();
  int n = 1;
  while (std::getline(in, line)) {
    ++n;
    std::stringstream s(line);
    std::string f;
    std::vector<std::string> cols;
    while (std::getline(s, f, ',')) cols.push_back(f);
    if (cols.size() != 11) throw InputError(csv + ":" + std::to_string(n), "expected 11 columns");
    const double visual_d_mm = std::stod(cols[2]);
    items.push_back({{"kind", kind},
                     {"radius_m", 0.5e-3 * visual_d_mm},
                     {"p_world", {std::stod(cols[3]), std::stod(cols[4]), std::stod(cols[5])}},
                     {"v_world", {std::stod(cols[6]), std::stod(cols[7]), std::stod(cols[8])}}});
  }
  return items;
}

double psnr_of(double mse) { return mse > 0 ? 10.0 * std::log10(1.0 / mse) : 99.0; }

}  // namespace

int main(int argc, char** argv) {
  try {
    const Args a = parse(argc, argv);
    const Dataset ds = read_dataset(a.dataset);
    if (!ds.info.generator) throw InputError(a.dataset + "/dataset.json", "no generator block: not a generated dataset");
    const Json& gen = *ds.info.generator;
    const SceneSpec scene = read_scene_spec(gen.at("scene_spec").get<std::string>());
    const VariantSpec variant = scene.variant(gen.at("variant").get<std::string>());
    ProfileSpec profile = scene.profile(gen.at("profile").get<std::string>());
    profile.engine = "cycles";
    profile.samples = a.samples;
    Camera cam = ds.camera(a.view);

    Json items = Json::array();
    double weather_seconds = 0;
    for (const char* species : {"rain", "snow"}) {
      const std::string csv = ds.root + "/layers/particles_" + species + "/" + a.view + ".csv";
      if (!fs::exists(csv)) continue;
      for (auto& it : read_particles(csv, species)) items.push_back(it);
    }
    for (const auto& st : gen.at("stages"))
      if (st.value("name", "") == "rain" || st.value("name", "") == "snow") weather_seconds += st.value("seconds", 0.0);
    if (items.empty()) throw InputError(a.dataset, "no particles in the manifests of view " + a.view);

    // The third render repeats the weather view with another sampling seed: the PSNR between the two
    // Cycles layers is the Monte Carlo noise floor of the reference itself.
    Camera plain = cam, weather = cam, plain2 = cam, weather2 = cam;
    plain.name = a.view + "_plain";
    weather.name = a.view + "_weather";
    plain2.name = a.view + "_plain_seed2";
    weather2.name = a.view + "_weather_seed2";
    fs::create_directories(a.out);
    const std::string raw = fs::absolute(a.out).string() + "/render";
    fs::remove_all(raw);
    fs::create_directories(raw);
    Json job = blender_job(scene, variant, profile, {plain, weather, plain2, weather2}, {});
    for (int i = 0; i < 4; ++i) {
      job["camera"]["views"][i]["particles"] = i % 2 == 1;
      job["camera"]["views"][i]["seed"] = i < 2 ? 0 : 1;
    }
    job["particles"] = {{"exposure_s", cam.exposure_s}, {"items", items}};
    job["output_dir"] = raw;
    const std::string job_path = fs::absolute(a.out).string() + "/job.json";
    write_file_atomic(job_path, job.dump(1));
    ProcessOptions popts;
    popts.log_path = fs::absolute(a.out).string() + "/blender.log";
    fs::remove(popts.log_path);
    BlenderOptions bo;
    bo.script = std::string(WEATHERGS_SOURCE_DIR) + "/blender_scripts/render_scene.py";
    const ProcessResult r = run_process({a.blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python",
                                         bo.script, "--", job_path},
                                        "blender", popts);
    if (r.exit_code != 0) throw InputError("blender", "failed:\n" + tail_of_file(popts.log_path));
    const Json log = read_json_file(raw + "/render_log.json");
    const double cycles_plain_s = log["view_seconds"][0].get<double>();
    const double cycles_weather_s = log["view_seconds"][1].get<double>();

    const Image cyc0 = to_linear(read_image(raw + "/clean/" + plain.name + ".png"));
    const Image cyc1 = to_linear(read_image(raw + "/clean/" + weather.name + ".png"));
    const Image cyc2 = to_linear(read_image(raw + "/clean/" + plain2.name + ".png"));
    const Image cyc3 = to_linear(read_image(raw + "/clean/" + weather2.name + ".png"));
    const Image cpp0 = to_linear(read_image(ds.path(ImageKind::kClean, a.view)));
    const Image cpp1 = to_linear(read_image(ds.path(ImageKind::kImages, a.view)));
    // Layers are compared where both renderers agree on the scene: the C++ layer sits on the EEVEE
    // render, the Cycles layer on the Cycles render of the same view.
    double mse = 0, mse_zero = 0, mse_noise = 0, mean_cyc = 0, mean_cpp = 0, sum_cyc = 0, sum_cpp = 0;
    const size_t n = cyc0.data.size();
    for (size_t i = 0; i < n; ++i) {
      const double lc = cyc1.data[i] - cyc0.data[i];
      const double lc2 = cyc3.data[i] - cyc2.data[i];
      const double lp = cpp1.data[i] - cpp0.data[i];
      mse += (lc - lp) * (lc - lp);
      mse_zero += lc * lc;
      mse_noise += (lc - lc2) * (lc - lc2);
      mean_cyc += std::abs(lc);
      mean_cpp += std::abs(lp);
      sum_cyc += lc;
      sum_cpp += lp;
    }
    mse /= double(n), mse_zero /= double(n), mse_noise /= double(n), mean_cyc /= double(n), mean_cpp /= double(n);
    sum_cyc /= double(n), sum_cpp /= double(n);
    // The same on 4x4 box-averaged layers: Monte Carlo noise of the thin motion-blurred streaks drops
    // ~4x in amplitude, the structure (where the weather adds light, how much) stays.
    auto box4 = [&](const Image& a, const Image& b) {
      Image out(a.width / 4, a.height / 4, a.channels, ColorSpace::kLinear);
      for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x)
          for (int c = 0; c < a.channels; ++c) {
            double sum = 0;
            for (int dy = 0; dy < 4; ++dy)
              for (int dx = 0; dx < 4; ++dx) sum += a.at(4 * x + dx, 4 * y + dy, c) - b.at(4 * x + dx, 4 * y + dy, c);
            out.at(x, y, c) = float(sum / 16.0);
          }
      return out;
    };
    const Image bc = box4(cyc1, cyc0), bc2 = box4(cyc3, cyc2), bp = box4(cpp1, cpp0);
    double bmse = 0, bmse_noise = 0, bmse_zero = 0;
    for (size_t i = 0; i < bc.data.size(); ++i) {
      bmse += double(bc.data[i] - bp.data[i]) * (bc.data[i] - bp.data[i]);
      bmse_noise += double(bc.data[i] - bc2.data[i]) * (bc.data[i] - bc2.data[i]);
      bmse_zero += double(bc.data[i]) * bc.data[i];
    }
    const double bn = double(bc.data.size());
    const double cpp_per_view_s = weather_seconds / double(ds.cameras.size());
    const Json result = {{"dataset", ds.info.name},
                         {"view", a.view},
                         {"particles", items.size()},
                         {"cycles_samples", a.samples},
                         {"psnr_weather_layer_db", psnr_of(mse)},
                         {"psnr_no_weather_baseline_db", psnr_of(mse_zero)},
                         {"psnr_cycles_seed_vs_seed_db", psnr_of(mse_noise)},
                         {"psnr_weather_layer_box4_db", psnr_of(bmse / bn)},
                         {"psnr_cycles_seed_vs_seed_box4_db", psnr_of(bmse_noise / bn)},
                         {"psnr_no_weather_baseline_box4_db", psnr_of(bmse_zero / bn)},
                         {"mean_layer_cycles", sum_cyc},
                         {"mean_layer_cpp", sum_cpp},
                         {"mean_abs_layer_cycles", mean_cyc},
                         {"mean_abs_layer_cpp", mean_cpp},
                         {"cycles_seconds_with_particles", cycles_weather_s},
                         {"cycles_seconds_plain", cycles_plain_s},
                         {"cpp_weather_seconds_per_view", cpp_per_view_s},
                         {"time_ratio_cycles_over_cpp", cycles_weather_s / std::max(cpp_per_view_s, 1e-9)}};
    write_file_atomic(a.out + "/result.json", result.dump(1));
    std::printf("%s\n", result.dump(1).c_str());
    return 0;
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
}
