#include "capture/cycles_validation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/error.h"
#include "core/image.h"
#include "core/thin_lens.h"
#include "capture/blender.h"
#include "capture/process.h"
#include "capture/scene_spec.h"

namespace weathergs::capture {

namespace fs = std::filesystem;

namespace {

struct ManifestParticle {
  std::string id, kind;
  double radius_m = 0, camera_z_m = 0;
  Eigen::Vector3d p_world, v_world;
};

std::vector<ManifestParticle> read_particles(const std::string& csv, const std::string& kind) {
  std::ifstream in(csv);
  if (!in) throw InputError(csv, "particle manifest not found (generate with manifests on)");
  std::string line;
  std::getline(in, line);  // header: id,diameter_mm,visual_diameter_mm,x_m,y_m,z_m,vx_m_s,vy_m_s,vz_m_s,camera_z_m,visible
  std::vector<ManifestParticle> items;
  int n = 1;
  while (std::getline(in, line)) {
    ++n;
    std::stringstream s(line);
    std::string f;
    std::vector<std::string> cols;
    while (std::getline(s, f, ',')) cols.push_back(f);
    if (cols.size() != 11) throw InputError(csv + ":" + std::to_string(n), "expected 11 columns");
    ManifestParticle p;
    p.id = cols[0];
    p.kind = kind;
    p.radius_m = 0.5e-3 * std::stod(cols[2]);  // visual diameter
    p.p_world = {std::stod(cols[3]), std::stod(cols[4]), std::stod(cols[5])};
    p.v_world = {std::stod(cols[6]), std::stod(cols[7]), std::stod(cols[8])};
    p.camera_z_m = std::stod(cols[9]);
    items.push_back(p);
  }
  return items;
}

double psnr_of(double mse) { return mse > 0 ? 10.0 * std::log10(1.0 / mse) : 99.0; }

// layer = a - b, 3 channels.
Image difference(const Image& a, const Image& b) {
  Image out(a.width, a.height, 3, ColorSpace::kLinear);
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x)
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = a.at(x, y, c) - b.at(x, y, c);
  return out;
}

// 4x4 box average: Monte Carlo noise of the thin motion-blurred streaks drops ~4x in amplitude, the
// structure (where the weather adds or takes light, how much) stays.
Image box4(const Image& a) {
  Image out(a.width / 4, a.height / 4, 3, ColorSpace::kLinear);
  for (int y = 0; y < out.height; ++y)
    for (int x = 0; x < out.width; ++x)
      for (int c = 0; c < 3; ++c) {
        double sum = 0;
        for (int dy = 0; dy < 4; ++dy)
          for (int dx = 0; dx < 4; ++dx) sum += a.at(4 * x + dx, 4 * y + dy, c);
        out.at(x, y, c) = float(sum / 16.0);
      }
  return out;
}

double mse_of(const Image& a, const Image* b) {
  double sum = 0;
  for (size_t i = 0; i < a.data.size(); ++i) {
    const double d = a.data[i] - (b ? b->data[i] : 0.f);
    sum += d * d;
  }
  return sum / double(a.data.size());
}

// A particle's projected linear path over the exposure and the capsule around it that holds its streak
// (its image radius, defocus and 1.5 px of pixel footprint).
struct Capsule {
  Eigen::Vector2d a, b;
  double radius_px = 0;
  bool contains(const Eigen::Vector2d& q, double* t) const {
    const Eigen::Vector2d d = b - a;
    *t = std::clamp((q - a).dot(d) / std::max(d.squaredNorm(), 1e-12), 0.0, 1.0);
    return (q - a - *t * d).norm() <= radius_px;
  }
  // Pixels of the image whose centre is inside, in row-major order.
  template <class F>
  void for_each_pixel(int width, int height, F&& f) const {
    const int x0 = std::max(0, int(std::floor(std::min(a.x(), b.x()) - radius_px)));
    const int x1 = std::min(width - 1, int(std::ceil(std::max(a.x(), b.x()) + radius_px)));
    const int y0 = std::max(0, int(std::floor(std::min(a.y(), b.y()) - radius_px)));
    const int y1 = std::min(height - 1, int(std::ceil(std::max(a.y(), b.y()) + radius_px)));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        double t;
        if (contains({x + 0.5, y + 0.5}, &t)) f(x, y, t);
      }
  }
};

constexpr int kStreakSegments = 10;  // tenths of a path, each mostly clear of other streaks (below)

// Where along the path the streak lies: the path parameters below which 10% and 90% of the layer's
// |value| inside the capsule lie, in pixels from the path's start, over the pixels no other
// particle's capsule touches (`shared` counts capsules per pixel). Robust to Monte Carlo noise (a
// quantile of the whole streak, not a threshold per pixel).
struct Extent {
  double start_px = 0, end_px = 0;
  bool found = false;
};
Extent streak_extent(const Image& layer, const Capsule& c, const std::vector<int>& shared) {
  std::vector<std::pair<double, double>> mass;  // (t, |layer|)
  double total = 0;
  c.for_each_pixel(layer.width, layer.height, [&](int x, int y, double t) {
    if (shared[size_t(y) * layer.width + x] != 1) return;
    double m = 0;
    for (int ch = 0; ch < 3; ++ch) m += std::abs(layer.at(x, y, ch));
    if (m > 0) mass.push_back({t, m}), total += m;
  });
  Extent e;
  if (!(total > 0)) return e;
  std::sort(mass.begin(), mass.end());
  const double len = (c.b - c.a).norm();
  double acc = 0;
  bool have_start = false;
  for (const auto& [t, m] : mass) {
    acc += m;
    if (!have_start && acc >= 0.1 * total) e.start_px = t * len, have_start = true;
    if (acc >= 0.9 * total) {
      e.end_px = t * len;
      break;
    }
  }
  e.found = true;
  return e;
}

}  // namespace

void CyclesValidationOptions::validate() const {
  if (dataset.empty()) throw InputError("dataset", "required");
  if (blender_script.empty()) throw InputError("blender_script", "required (blender_scripts/render_scene.py)");
  if (samples < 1) throw InputError("samples", "expected >= 1, got " + std::to_string(samples));
  if (nearest < 1) throw InputError("nearest", "expected >= 1, got " + std::to_string(nearest));
  if (coverage_samples < 0)
    throw InputError("coverage_samples", "expected >= 0 (0: " + std::to_string(kCoverageSampleFactor) +
                                             " x samples), got " + std::to_string(coverage_samples));
  if (!(glass_thickness_m >= 0 && glass_thickness_m <= 0.01))
    throw InputError("glass_thickness_m", "expected 0 (no plate) to 0.01 m, got " + std::to_string(glass_thickness_m));
  if (!(glass_refractive_index >= 1 && glass_refractive_index <= 2.5))
    throw InputError("glass_refractive_index", "expected 1 to 2.5, got " + std::to_string(glass_refractive_index));
}

Json validate_against_cycles(const CyclesValidationOptions& o) {
  o.validate();
  const Dataset ds = read_dataset(o.dataset);
  if (!ds.info.generator) throw InputError(o.dataset + "/dataset.json", "no generator block: not a generated dataset");
  const Json& gen = *ds.info.generator;
  const Json& effects = gen.at("spec").at("effects");
  // Two kinds: the particle layer (rain and/or snow) or the lens-drop layer (lens_droplets alone).
  const bool lens = effects.size() == 1 && effects.contains("lens_droplets");
  if (!lens)
    for (const auto& [effect, body] : effects.items())
      if (effect != "rain" && effect != "snow")
        throw InputError(o.dataset + "/dataset.json",
                         "the validation compares one layer alone, but the spec has \"" + effect +
                             "\" with others (make the dataset with rain and/or snow, or lens_droplets, only)");
  const SceneSpec scene = read_scene_spec(o.scene_spec.empty() ? gen.at("scene_spec").get<std::string>() : o.scene_spec);
  const VariantSpec variant = scene.variant(gen.at("variant").get<std::string>());
  ProfileSpec profile = scene.profile(gen.at("profile").get<std::string>());
  profile.engine = "cycles";
  profile.samples = o.samples;
  Camera cam = ds.camera(o.view);

  std::vector<ManifestParticle> particles;
  std::vector<std::string> species_present;
  // Seconds of the last generator stage of this name (the weather's own, after any earlier runs).
  auto stage_seconds = [&gen](const std::string& name) {
    double last = 0;
    for (const auto& st : gen.at("stages"))
      if (st.value("name", "") == name) last = st.value("seconds", 0.0);
    return last;
  };
  Json items = Json::array();
  double weather_seconds = 0;
  // Cycles renders the particles of the reference dataset when one is given: the same weather with a
  // lower visibility cutoff or near clip, so the light the generator leaves out is in the reference.
  const std::string ref_root = o.reference_dataset.empty() ? ds.root : read_dataset(o.reference_dataset).root;
  if (lens && ref_root != ds.root) throw InputError("reference_dataset", "applies to the particle layers only");
  for (const char* species : {"rain", "snow"}) {
    if (lens) break;
    const std::string csv = ds.root + "/layers/particles_" + species + "/" + o.view + ".csv";
    if (!fs::exists(csv)) continue;
    species_present.push_back(species);
    std::vector<ManifestParticle> drawn = read_particles(csv, species);
    if (ref_root != ds.root) {
      const std::string ref_csv = ref_root + "/layers/particles_" + species + "/" + o.view + ".csv";
      std::vector<ManifestParticle> ref = read_particles(ref_csv, species);
      std::set<std::string> ref_ids;
      for (const ManifestParticle& p : ref) ref_ids.insert(p.id);
      for (const ManifestParticle& p : drawn)
        if (!ref_ids.count(p.id))
          throw InputError(ref_csv, "lacks particle " + p.id + " of " + csv +
                                        ": the reference must be the same weather (spec, seed, view) drawn with a "
                                        "lower visibility_cutoff or near_m");
      drawn = std::move(ref);
    }
    for (const ManifestParticle& p : drawn) {
      particles.push_back(p);
      items.push_back({{"kind", p.kind},
                       {"radius_m", p.radius_m},
                       {"p_world", {p.p_world.x(), p.p_world.y(), p.p_world.z()}},
                       {"v_world", {p.v_world.x(), p.v_world.y(), p.v_world.z()}}});
    }
    // The latest run of the stage (a dataset re-weathered by `weathergs weather` lists earlier runs too).
    weather_seconds += stage_seconds(species);
  }
  Json lens_job;
  if (lens) {
    const Json& spec = effects.at("lens_droplets");
    if (spec.at("attach") != "lens" || spec.at("drop_side") != "scene" ||
        spec.at("glass_tilt_deg") != Json::array({0.0, 0.0}))
      throw InputError(o.dataset + "/dataset.json",
                       "the lens validation models drops on the scene side of an untilted glass attached to the lens");
    for (const Json& v : gen.at("lens_droplets").at("views"))
      if (v.at("view") == o.view)
        for (const Json& d : v.at("drops"))
          items.push_back({{"base_center_camera_m", d.at("base_center_camera_m")},
                           {"sphere_radius_m", 1e-3 * d.at("sphere_radius_mm").get<double>()},
                           {"contact_angle_deg", d.at("contact_angle_deg")}});
    lens_job = {{"refractive_index", spec.at("refractive_index")}, {"drops", items}};
    // The cover glass and the camera's front, sized to the view at the glass plus the lens aperture and
    // a margin (a larger pane centimetres from the camera could shade the scene near it from the sun).
    const double z = spec.at("glass_distance_m").get<double>();
    const double half_fov = std::max(0.5 * cam.width / cam.fx, 0.5 * cam.height / cam.fy);
    const double aperture = cam.f_number && cam.focal_length_mm ? 0.5e-3 * *cam.focal_length_mm / *cam.f_number : 0.0;
    const double half_size = 1.5 * z * half_fov + aperture + 2e-3;
    if (o.glass_thickness_m > 0)
      lens_job["glass_plate"] = {{"thickness_m", o.glass_thickness_m},
                                 {"refractive_index", o.glass_refractive_index},
                                 {"glass_distance_m", z},
                                 {"half_size_m", half_size}};
    if (o.camera_body) lens_job["camera_body"] = {{"half_size_m", half_size}};
    weather_seconds = stage_seconds("lens_droplets");
  }
  if (items.empty()) throw InputError(o.dataset, "no particles or lens drops recorded for view " + o.view);

  // The third render repeats the weather view with another sampling seed: the PSNR between the two
  // Cycles layers is the Monte Carlo noise floor of the reference itself.
  // A fifth render (particles only) gives their coverage: opaque white particles over a transparent
  // film, the scene a holdout (blender_scripts: CoverageMode).
  Camera plain = cam, weather = cam, plain2 = cam, weather2 = cam, coverage = cam;
  plain.name = o.view + "_plain";
  weather.name = o.view + "_weather";
  plain2.name = o.view + "_plain_seed2";
  weather2.name = o.view + "_weather_seed2";
  coverage.name = o.view + "_coverage";
  fs::create_directories(o.out_dir);
  const std::string raw = fs::absolute(o.out_dir).string() + "/render";
  std::vector<Camera> views = {plain, weather, plain2, weather2};
  if (!lens) views.push_back(coverage);
  // With a cover glass, a sixth render without it gives the glass's transmission (below).
  const bool glass = lens && o.glass_thickness_m > 0;
  Camera no_glass = cam;
  no_glass.name = o.view + "_plain_no_glass";
  if (glass) views.push_back(no_glass);
  Json job = blender_job(scene, variant, profile, views, {});
  for (int i = 0; i < 4; ++i) {
    job["camera"]["views"][i][lens ? "lens" : "particles"] = i % 2 == 1;
    job["camera"]["views"][i]["seed"] = i < 2 ? 0 : 1;
  }
  const int coverage_samples = o.coverage_samples > 0 ? o.coverage_samples : kCoverageSampleFactor * o.samples;
  if (!lens) {
    job["camera"]["views"][4]["coverage"] = true;
    job["camera"]["views"][4]["samples"] = coverage_samples;
  }
  if (glass) {  // views[4] is no_glass: lens jobs have no coverage view
    job["camera"]["views"][4]["lens"] = false;
    job["camera"]["views"][4]["glass"] = false;
  }
  if (lens) {
    job["lens_drops"] = lens_job;
    // The drops sit centimetres from the pinhole: inside the scene renders' near clip.
    job["camera"]["clip_start_m"] = 1e-4;
  }
  else job["particles"] = {{"exposure_s", cam.exposure_s}, {"items", items}};
  if (gen.at("spec").at("effects").contains("snow")) {
    const Json& snow = gen.at("spec").at("effects").at("snow");
    job["particles"]["snow"] = {{"albedo", snow.at("appearance").value("albedo", 0.9)},
                                {"opacity", snow.value("opacity", 1.0)}};
  }
  job["render"]["float_images"] = true;
  // The generator defocuses particles through the camera's lens when the spec says so: so does Cycles.
  const bool defocus = (lens ? effects.at("lens_droplets").value("defocus", false)
                             : gen.at("spec").at("render").value("defocus", false)) &&
                       cam.f_number && cam.focus_distance_m;
  if (defocus) job["camera"]["dof"] = {{"focus_distance_m", *cam.focus_distance_m}, {"f_number", *cam.f_number}};
  job["output_dir"] = raw;
  const std::string job_path = fs::absolute(o.out_dir).string() + "/job.json";
  // Renders of the same job (same particles, scene, samples) are reused when asked: the comparison
  // can change without re-running Cycles. render_log.json is written last, so its presence means
  // the renders are complete.
  const bool reuse = o.reuse_renders && fs::exists(raw + "/render_log.json") && fs::exists(job_path) &&
                     read_json_file(job_path) == job;
  if (!reuse) {
    fs::remove_all(raw);
    fs::create_directories(raw);
    write_file_atomic(job_path, job.dump(1));
    ProcessOptions popts;
    popts.log_path = fs::absolute(o.out_dir).string() + "/blender.log";
    fs::remove(popts.log_path);
    const ProcessResult r = run_blender_job(o.blender, o.blender_script, job_path, "blender", popts);
    if (r.exit_code != 0) throw InputError("blender", "failed:\n" + tail_of_file(popts.log_path));
  }
  const Json log = read_json_file(raw + "/render_log.json");
  const double cycles_plain_s = log["view_seconds"][0].get<double>();
  const double cycles_weather_s = log["view_seconds"][1].get<double>();

  auto cycles = [&](const Camera& c) { return read_image(raw + "/clean/" + c.name + ".exr"); };
  const Image plain_render = cycles(plain);
  Image lc = difference(cycles(weather), plain_render);
  Image lc2 = difference(cycles(weather2), cycles(plain2));
  // The dataset's clean view is what the camera sees without drops, through its cover glass (the
  // generator's convention): the glass's transmission T is in it. Ours was rendered without a glass,
  // so the Cycles layers (seen through it) are divided by T, measured as the ratio of the plain
  // renders with and without the glass (the same sampling seed).
  double glass_transmission = 1;
  if (glass) {
    const Image without = cycles(no_glass);
    double a = 0, b = 0;
    for (size_t i = 0; i < plain_render.data.size(); ++i) a += plain_render.data[i], b += without.data[i];
    if (!(a > 0 && b > 0)) throw InputError(raw, "the plain Cycles renders are black: cannot measure the glass's transmission");
    glass_transmission = a / b;
    for (float& v : lc.data) v = float(v / glass_transmission);
    for (float& v : lc2.data) v = float(v / glass_transmission);
  }
  // The C++ layer in float: the stages' compositing, (1 - A) below + A L per species in stage order,
  // replayed from the float layers on the clean view. (The 8-bit images would quantize the faint
  // physical streaks away.)
  const Image clean = to_linear(to_rgb(read_image(ds.path(ImageKind::kClean, o.view))));
  // Lens drops change the image by far more than an 8-bit level: their layer is images - clean.
  Image composite = lens ? to_linear(to_rgb(read_image(ds.path(ImageKind::kImages, o.view)))) : clean;
  // The particles' coverage, 1 - prod(1 - alpha) over the species (3 equal channels, as Cycles').
  Image coverage_cpp(clean.width, clean.height, 3);
  std::fill(coverage_cpp.data.begin(), coverage_cpp.data.end(), 1.f);
  for (const std::string& species : species_present) {
    const std::string light_path = ds.root + "/layers/" + species + "_radiance/" + o.view + ".exr";
    if (!fs::exists(light_path))
      throw InputError(light_path, "missing: the float radiance layer of the particles (re-run `weathergs weather` "
                                   "with layers on; datasets made before it existed lack it)");
    const Image alpha = read_image(ds.root + "/layers/" + species + "_alpha/" + o.view + ".exr");
    const Image light = read_image(light_path);
    for (size_t p = 0; p < composite.num_pixels(); ++p)
      for (int c = 0; c < 3; ++c) {
        float& v = composite.data[p * 3 + c];
        v = (1 - alpha.data[p]) * v + alpha.data[p] * light.data[p * 3 + c];
        coverage_cpp.data[p * 3 + c] *= 1 - alpha.data[p];
      }
  }
  for (float& v : coverage_cpp.data) v = 1 - v;
  const Image lp = difference(composite, clean);

  const Image bc = box4(lc), bc2 = box4(lc2), bp = box4(lp);
  // Energy: RMS of the 4x4-averaged layer; Cycles' corrected for its noise (the seed-vs-seed MSE is
  // twice the noise variance of one render).
  const double noise_var_box = mse_of(bc, &bc2) / 2;
  const double energy_cycles = std::sqrt(std::max(0.0, mse_of(bc, nullptr) - noise_var_box));
  const double energy_cpp = std::sqrt(mse_of(bp, nullptr));
  // Where each layer changes the view noticeably (any channel by more than kChanged in linear radiance,
  // ~5 8-bit levels at mid grey) on the 4x4-averaged layers, and how well the two regions overlap.
  constexpr float kChanged = 0.02f;
  int64_t changed_both = 0, changed_any = 0, changed_cyc = 0, changed_cpp = 0;
  for (size_t p = 0; p < bc.num_pixels(); ++p) {
    bool a = false, b = false;
    for (int c = 0; c < 3; ++c) {
      a = a || std::abs(bc.data[p * 3 + c]) > kChanged;
      b = b || std::abs(bp.data[p * 3 + c]) > kChanged;
    }
    changed_both += a && b, changed_any += a || b, changed_cyc += a, changed_cpp += b;
  }
  double mean_cyc = 0, mean_cpp = 0;
  for (size_t i = 0; i < lc.data.size(); ++i) mean_cyc += lc.data[i], mean_cpp += lp.data[i];
  mean_cyc /= double(lc.data.size()), mean_cpp /= double(lc.data.size());

  // Streak extents of the nearest particles whose paths lie inside the image (an extent cut by the
  // frame says nothing about the renderer) and clear of other particles' streaks along the whole
  // path: at most half of the pixels of each tenth of the capsule (by path parameter) may lie under
  // another capsule. The quantiles are taken over the particle's own pixels, so a stretch buried
  // under other streaks would leave a few noisy pixels to decide where the streak ends (measured:
  // 4.1 px "errors" at the buried end of a rain-100 streak whose ends agree within 1 px when every
  // pixel is counted; benchmarks/README.md).
  const std::optional<ThinLens> thin_lens = defocus ? thin_lens_of(cam) : std::nullopt;
  const double f = std::sqrt(cam.fx * cam.fy);
  std::vector<std::optional<Capsule>> capsules(particles.size());
  std::vector<int> shared(size_t(cam.width) * cam.height, 0);
  for (size_t i = 0; i < particles.size(); ++i) {
    const ManifestParticle& p = particles[i];
    const Eigen::Vector3d c0 = cam.to_camera(p.p_world), c1 = cam.to_camera(p.p_world + p.v_world * cam.exposure_s);
    if (!(c0.z() > 0.05 && c1.z() > 0.05)) continue;
    const double z = 0.5 * (c0.z() + c1.z()), r_px = f * p.radius_m / z, coc = thin_lens ? thin_lens->coc_radius_px(f, z) : 0.0;
    capsules[i] = Capsule{cam.project_camera(c0), cam.project_camera(c1), 1.5 + std::sqrt(r_px * r_px + coc * coc)};
    capsules[i]->for_each_pixel(cam.width, cam.height, [&](int x, int y, double) { ++shared[size_t(y) * cam.width + x]; });
  }
  std::vector<size_t> order(particles.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t x, size_t y) { return particles[x].camera_z_m < particles[y].camera_z_m; });
  Json streaks = Json::array();
  std::vector<double> end_errors, coverage_end_errors;
  const Image coverage_cycles = lens ? Image() : cycles(coverage);
  auto inside = [&](const Eigen::Vector2d& u) { return u.x() >= 0 && u.y() >= 0 && u.x() < cam.width && u.y() < cam.height; };
  for (size_t i : order) {
    if (int(streaks.size()) >= o.nearest) break;
    if (!capsules[i] || !inside(capsules[i]->a) || !inside(capsules[i]->b)) continue;
    std::array<int, kStreakSegments> own{}, all{};
    capsules[i]->for_each_pixel(cam.width, cam.height, [&](int x, int y, double t) {
      const int seg = std::min(kStreakSegments - 1, int(t * kStreakSegments));
      ++all[seg];
      own[seg] += shared[size_t(y) * cam.width + x] == 1;
    });
    bool buried = false;  // some tenth more than half under other streaks
    for (int seg = 0; seg < kStreakSegments; ++seg) buried = buried || 2 * own[seg] < all[seg];
    if (buried) continue;
    const Extent ec = streak_extent(lc, *capsules[i], shared), ep = streak_extent(lp, *capsules[i], shared);
    if (!ec.found || !ep.found) continue;
    const double err = std::max(std::abs(ec.start_px - ep.start_px), std::abs(ec.end_px - ep.end_px));
    end_errors.push_back(err);
    // The same quantiles on the coverage: where the particle is, whatever light it shows.
    const Extent cc = streak_extent(coverage_cycles, *capsules[i], shared);
    const Extent cp = streak_extent(coverage_cpp, *capsules[i], shared);
    const double cov_err = cc.found && cp.found
                               ? std::max(std::abs(cc.start_px - cp.start_px), std::abs(cc.end_px - cp.end_px))
                               : std::numeric_limits<double>::infinity();  // one side sees nothing: a miss
    coverage_end_errors.push_back(cov_err);
    streaks.push_back({{"kind", particles[i].kind},
                       {"camera_z_m", particles[i].camera_z_m},
                       {"path_px", (capsules[i]->b - capsules[i]->a).norm()},
                       {"cycles_px", {ec.start_px, ec.end_px}},
                       {"cpp_px", {ep.start_px, ep.end_px}},
                       {"max_end_error_px", err},
                       {"cycles_coverage_px", {cc.start_px, cc.end_px}},
                       {"cpp_coverage_px", {cp.start_px, cp.end_px}},
                       {"max_coverage_end_error_px", std::isfinite(cov_err) ? Json(cov_err) : Json(nullptr)}});
  }
  auto median_and_max = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? std::pair<double, double>{0, 0} : std::pair<double, double>{v[v.size() / 2], v.back()};
  };
  const auto [median_err, max_err] = median_and_max(end_errors);
  const auto [cov_median_err, cov_max_err] = median_and_max(coverage_end_errors);
  auto finite_or_null = [](double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); };

  const double cpp_per_view_s = weather_seconds / double(ds.cameras.size());
  const double psnr_box = psnr_of(mse_of(bc, &bp)), psnr_box_zero = psnr_of(mse_of(bc, nullptr));
  Json result = {{"dataset", ds.info.name},
                       {"reference_particles_from", ref_root},
                       {"layer", lens ? "lens_droplets" : "particles"},
                       {"view", o.view},
                       {lens ? "lens_drops" : "particles", items.size()},
                       {"cycles_samples", o.samples},
                       {"cycles_coverage_samples", lens ? 0 : coverage_samples},
                       {"depth_of_field", defocus},
                       {"psnr_weather_layer_db", psnr_of(mse_of(lc, &lp))},
                       {"psnr_no_weather_baseline_db", psnr_of(mse_of(lc, nullptr))},
                       {"psnr_cycles_seed_vs_seed_db", psnr_of(mse_of(lc, &lc2))},
                       {"psnr_weather_layer_box4_db", psnr_box},
                       {"psnr_no_weather_baseline_box4_db", psnr_box_zero},
                       {"psnr_cycles_seed_vs_seed_box4_db", psnr_of(mse_of(bc, &bc2))},
                       {"gain_over_no_weather_box4_db", psnr_box - psnr_box_zero},
                       {"changed_fraction_cycles", double(changed_cyc) / double(bc.num_pixels())},
                       {"changed_fraction_cpp", double(changed_cpp) / double(bc.num_pixels())},
                       {"changed_iou", changed_any > 0 ? double(changed_both) / double(changed_any) : 1.0},
                       {"mean_layer_cycles", mean_cyc},
                       {"mean_layer_cpp", mean_cpp},
                       {"energy_box4_cycles", energy_cycles},
                       {"energy_box4_cpp", energy_cpp},
                       {"energy_ratio_cpp_over_cycles", energy_cycles > 0 ? energy_cpp / energy_cycles : 0.0},
                       {"streaks_compared", streaks.size()},
                       {"streak_end_error_median_px", median_err},
                       {"streak_end_error_max_px", max_err},
                       {"coverage_streak_end_error_median_px", finite_or_null(cov_median_err)},
                       {"coverage_streak_end_error_max_px", finite_or_null(cov_max_err)},
                       {"streaks", streaks},
                       {"cycles_seconds_with_particles", cycles_weather_s},
                       {"cycles_seconds_plain", cycles_plain_s},
                       {"cpp_weather_seconds_per_view", cpp_per_view_s},
                       {"time_ratio_cycles_over_cpp", cycles_weather_s / std::max(cpp_per_view_s, 1e-9)}};
  if (lens)
    for (const char* key : {"streaks", "streaks_compared", "streak_end_error_median_px", "streak_end_error_max_px",
                            "coverage_streak_end_error_median_px", "coverage_streak_end_error_max_px"})
      result.erase(key);
  if (lens) {
    result["glass_plate_mm"] = 1e3 * o.glass_thickness_m;
    result["glass_transmission"] = glass_transmission;
    result["camera_body"] = o.camera_body;
  }
  write_file_atomic(o.out_dir + "/result.json", result.dump(1));
  return result;
}

}  // namespace weathergs::capture
