#include "reconstruction/run.h"

#include <chrono>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/colmap_model.h"
#include "core/error.h"
#include "core/image.h"

namespace weathergs::recon {

namespace fs = std::filesystem;

namespace {

constexpr const char* kRunFormat = "weathergs-3dgs-run";
constexpr int kRunVersion = 1;

std::string view_file(const Dataset& d, const std::string& choice, const std::string& view,
                      const std::vector<std::string>& named_folders) {
  for (const std::string& f : named_folders)
    if (choice == f) return d.path(f == "lens" ? "masks/lens" : f, view);
  return (fs::path(choice) / (view + ".png")).string();
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

Json run_json(const TrainRunOptions& o, const Trainer& t, double seconds, bool complete, const std::string& init) {
  return Json{{"format", kRunFormat},
              {"version", kRunVersion},
              {"complete", complete},
              {"dataset", fs::absolute(o.dataset).lexically_normal().string()},
              {"images", o.images},
              {"masks", o.masks},
              {"initialization", init},
              {"iterations", t.iteration()},
              {"sh_degree", t.sh_degree()},
              {"num_gaussians", t.gaussians().size()},
              {"train_seconds", seconds},
              {"peak_rss_mb", peak_rss_mb()},
              {"extent", t.extent()},
              {"options", t.options().to_json()}};
}

struct RunInfo {
  std::string dataset, images, masks;
  int iterations = 0, sh_degree = 0;
  int64_t num_gaussians = 0;
  double train_seconds = 0, peak_rss_mb = 0;
  bool complete = false;
  TrainOptions options;
};

RunInfo read_run_json(const std::string& run_dir) {
  const std::string path = (fs::path(run_dir) / "run.json").string();
  if (!fs::exists(path)) throw InputError(path, "missing: not a training run folder");
  JsonReader r = JsonReader::from_file(path);
  if (r.get<std::string>("format") != kRunFormat) throw InputError(r.where("format"), std::string("expected ") + kRunFormat);
  if (r.get<int>("version") != kRunVersion) throw InputError(r.where("version"), "unsupported version");
  RunInfo info;
  info.complete = r.get<bool>("complete");
  info.dataset = r.get<std::string>("dataset");
  info.images = r.get<std::string>("images");
  info.masks = r.get<std::string>("masks");
  r.get<std::string>("initialization");
  info.iterations = r.get<int>("iterations");
  info.sh_degree = r.get<int>("sh_degree");
  if (info.sh_degree < 0 || info.sh_degree > kMaxShDegree) throw InputError(r.where("sh_degree"), "expected 0..3");
  info.num_gaussians = r.get<int64_t>("num_gaussians");
  info.train_seconds = r.get<double>("train_seconds");
  info.peak_rss_mb = r.get<double>("peak_rss_mb");
  r.get<double>("extent");
  info.options = TrainOptions::from_json(r.child("options"));
  r.finish();
  return info;
}

}  // namespace

std::vector<TrainView> load_train_views(const Dataset& dataset, const std::string& images, const std::string& masks) {
  std::vector<TrainView> views;
  const auto& names = dataset.split("train");
  if (names.empty()) throw InputError(dataset.root + "/dataset.json:/splits/train", "the train split is empty");
  for (const std::string& name : names) {
    TrainView v;
    v.camera = dataset.camera(name);
    const std::string ipath = view_file(dataset, images, name, {"images", "clean"});
    const Image img = to_rgb(read_image(ipath));
    if (img.width != v.camera.width || img.height != v.camera.height)
      throw InputError(ipath, "image is " + img.to_string() + ", camera '" + name + "' expects " +
                                  std::to_string(v.camera.width) + "x" + std::to_string(v.camera.height));
    require_finite(img, ipath);
    v.rgb.assign(img.data.begin(), img.data.end());
    for (float& x : v.rgb) x = std::clamp(x, 0.f, 1.f);
    if (masks != "none") {
      const std::string mpath = view_file(dataset, masks, name, {"lens"});
      const Image m = read_mask(mpath);
      if (m.width != v.camera.width || m.height != v.camera.height)
        throw InputError(mpath, "mask is " + m.to_string() + ", expected the camera's size");
      v.invalid.resize(m.num_pixels());
      for (size_t p = 0; p < m.num_pixels(); ++p) v.invalid[p] = m.data[p] > 0.5f ? 1 : 0;
    }
    views.push_back(std::move(v));
  }
  return views;
}

GaussianSet<float> initial_gaussians(const Dataset& dataset, const TrainOptions& options, std::string* source) {
  const std::string path = (fs::path(dataset.root) / "sparse/0/points3D.txt").string();
  if (fs::exists(path)) {
    const std::vector<ColmapPoint3D> pts = read_colmap_points3d(path);
    if (!pts.empty()) {
      std::vector<Eigen::Vector3d> xyz, rgb;
      for (const ColmapPoint3D& p : pts) {
        xyz.push_back(p.xyz);
        rgb.push_back(p.rgb / 255.0);
      }
      *source = "colmap:" + std::to_string(pts.size());
      return init_from_points(xyz, rgb);
    }
  }
  std::vector<Camera> train_cams;
  for (const std::string& v : dataset.split("train")) train_cams.push_back(dataset.camera(v));
  *source = "random:" + std::to_string(options.random_init_count);
  return init_random(train_cams, options.random_init_count, options.seed, options.random_init_near_m,
                     options.random_init_far_m);
}

TrainRunResult train_run(const TrainRunOptions& o, const IterationCallback& on_iteration) {
  o.train.validate("train options");
  if (o.checkpoint_every < 0) throw InputError("--checkpoint-every", "must be >= 0");
  const Dataset dataset = read_dataset(o.dataset);
  std::vector<TrainView> views = load_train_views(dataset, o.images, o.masks);
  std::vector<Camera> cams;
  for (const TrainView& v : views) cams.push_back(v.camera);
  const double extent = scene_extent(cams);

  const fs::path run(o.out);
  const std::string ckpt = (run / "checkpoint.bin").string(), ply = (run / "point_cloud.ply").string(),
                    info = (run / "run.json").string();
  const bool has_run = fs::exists(ckpt) || fs::exists(info);
  if (has_run && !o.resume && !o.force)
    throw InputError(o.out, "already holds a training run: pass --resume to continue it or --force to start over");
  if (o.resume && !fs::exists(ckpt)) throw InputError(ckpt, "missing: nothing to resume");
  if (o.force && !o.resume)
    for (const std::string& f : {ckpt, ply, info}) fs::remove(f);
  fs::create_directories(run);

  std::string init;
  GaussianSet<float> initial = initial_gaussians(dataset, o.train, &init);
  Trainer trainer(std::move(views), std::move(initial), o.train, extent);
  double seconds_before = 0;
  if (o.resume) {
    const RunInfo ri = read_run_json(o.out);
    if (ri.images != o.images || ri.masks != o.masks ||
        fs::path(ri.dataset) != fs::absolute(o.dataset).lexically_normal())
      throw InputError(info, "the run was trained on dataset " + ri.dataset + " with images '" + ri.images +
                                 "' and masks '" + ri.masks + "': resume with the same inputs");
    seconds_before = trainer.load_checkpoint(ckpt);
  }
  const auto t0 = std::chrono::steady_clock::now();
  auto save = [&](bool complete) {
    const double s = seconds_before + seconds_since(t0);
    trainer.save_checkpoint(ckpt, s);
    write_ply(ply, trainer.gaussians());
    write_file_atomic(info, run_json(o, trainer, s, complete, init).dump(2) + "\n");
  };
  TrainRunResult result;
  while (trainer.iteration() < o.train.iterations) {
    const IterationStats st = trainer.step();
    result.final_loss = st.loss;
    result.final_psnr = st.psnr;
    if (on_iteration) on_iteration(st);
    if (o.checkpoint_every > 0 && st.iteration % o.checkpoint_every == 0 && st.iteration < o.train.iterations)
      save(false);
  }
  save(true);
  result.iterations = trainer.iteration();
  result.num_gaussians = int64_t(trainer.gaussians().size());
  result.train_seconds = seconds_before + seconds_since(t0);
  result.peak_rss_mb = peak_rss_mb();
  return result;
}

TrainRunOptions read_run_options(const std::string& run_dir) {
  const RunInfo ri = read_run_json(run_dir);
  TrainRunOptions o;
  o.dataset = ri.dataset;
  o.images = ri.images;
  o.masks = ri.masks;
  o.out = run_dir;
  o.train = ri.options;
  return o;
}

RenderRunResult render_run(const RenderRunOptions& o) {
  const RunInfo ri = read_run_json(o.model);
  const GaussianSet<float> g = read_ply((fs::path(o.model) / "point_cloud.ply").string());
  const Dataset dataset = read_dataset(o.dataset.empty() ? ri.dataset : o.dataset);
  const auto& names = dataset.split(o.split);
  RasterSettings<float> rs;
  rs.sh_degree = ri.sh_degree;
  for (int c = 0; c < 3; ++c) rs.background[c] = float(ri.options.background[c]);
  AtomicDirectory dir(o.out);
  RasterState<float> state;
  RenderRunResult result;
  for (const std::string& name : names) {
    const Camera& cam = dataset.camera(name);
    const auto t0 = std::chrono::steady_clock::now();
    rasterize_forward(g, RasterCamera<float>::from(cam), rs, &state);
    result.render_seconds += seconds_since(t0);
    Image img(cam.width, cam.height, 3);
    for (size_t i = 0; i < img.data.size(); ++i) img.data[i] = std::clamp(state.image[i], 0.f, 1.f);
    write_image((fs::path(dir.path()) / (name + ".png")).string(), img);
    ++result.views;
  }
  const Json info{{"method", o.method},
                  {"train_seconds", ri.train_seconds},
                  {"peak_rss_mb", std::max(ri.peak_rss_mb, peak_rss_mb())},
                  {"num_gaussians", g.size()},
                  {"iterations", ri.iterations},
                  {"render_seconds", result.render_seconds}};
  write_file_atomic((fs::path(dir.path()) / "info.json").string(), info.dump(2) + "\n");
  dir.commit();
  return result;
}

}  // namespace weathergs::recon
