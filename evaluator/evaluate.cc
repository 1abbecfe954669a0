#include "evaluator/evaluate.h"

#include <filesystem>
#include <set>

#include "core/dataset.h"
#include "core/parallel.h"
#include "core/progress.h"
#include "core/sha256.h"
#include "core/version.h"

namespace weathergs::evaluator {

namespace fs = std::filesystem;

MetricValues score_pair(const Image& render, const Image& gt, const ScoringOptions& o, Lpips* lpips,
                        const Image* mask, const std::string& where) {
  // Both images become RGB, sRGB-encoded (metrics are defined on display values), then optionally
  // quantized to 8 bits.
  Image a = to_srgb(to_rgb(render)), b = to_srgb(to_rgb(gt));
  require_comparable(a, b, mask, where);
  require_finite(a, where + " (render)");
  require_finite(b, where + " (ground truth)");
  if (o.quantize_uint8) {
    a = quantize_uint8(a);
    b = quantize_uint8(b);
  } else {
    for (Image* im : {&a, &b})
      for (float& v : im->data) v = std::min(1.f, std::max(0.f, v));
  }
  MetricValues m;
  try {
    m.psnr = psnr(a, b, mask);
    m.ssim = ssim(a, b, o.ssim, mask);
    if (o.lpips) {
      WGS_CHECK(lpips != nullptr);
      if (mask) {  // masked: the excluded pixels of the render take the truth's values (Protocol::lpips_mask)
        for (int y = 0; y < a.height; ++y)
          for (int x = 0; x < a.width; ++x)
            if (mask->at(x, y) >= 0.5f)
              for (int c = 0; c < a.channels; ++c) a.at(x, y, c) = b.at(x, y, c);
      }
      m.lpips = lpips->distance(a, b);
    }
  } catch (const InputError& e) {
    throw InputError(where, e.problem());
  }
  return m;
}

std::string hash_view_files(const std::vector<std::string>& views, const std::vector<std::string>& paths) {
  WGS_CHECK(views.size() == paths.size());
  Sha256 h;
  for (size_t i = 0; i < views.size(); ++i) h.update(views[i] + " " + sha256_file(paths[i]) + "\n");
  return h.hex_digest();
}

void EvaluateOptions::validate() const {
  const std::string where = "evaluate options";
  if (gt_dataset.empty()) throw InputError(where, "gt_dataset is empty: the dataset folder is required");
  if (renders_dir.empty()) throw InputError(where, "renders_dir is empty: the renders folder is required");
  if (split.empty()) throw InputError(where, "split is empty");
  if (ground_truth != ImageKind::kClean && ground_truth != ImageKind::kImages &&
      ground_truth != ImageKind::kTargetNoParticles && ground_truth != ImageKind::kTargetLensOnly)
    throw InputError(where, std::string("ground_truth is ") + to_string(ground_truth) +
                                ": must be clean, images or a target (target_no_particles, target_lens_only)");
}

void check_scoring_resources(const ScoringOptions& options) {
  if (!options.lpips) return;
  const Lpips probe(find_lpips_model(options.lpips_model_search));
  (void)probe;
}

Protocol scoring_protocol(const EvaluateOptions& o) {
  Protocol p;
  p.ssim = o.scoring.ssim.protocol_name();
  p.lpips = o.scoring.lpips ? std::optional<std::string>("alex_v0.1") : std::nullopt;
  p.quantize_uint8 = o.scoring.quantize_uint8;
  p.split = o.split;
  if (o.ground_truth != ImageKind::kClean) p.ground_truth = folder_of(o.ground_truth);
  if (o.mask_dir) {
    p.mask = fs::path(*o.mask_dir).lexically_normal().filename().string();
    p.lpips_mask = kLpipsTruthFilled;
  }
  return p;
}

ScoredDataset identify_dataset(const Dataset& ds, bool allow_changed) {
  ScoredDataset out;
  const DatasetIdentity found = compute_dataset_identity(ds.root);
  if (ds.info.identity) {
    const std::string where = ds.file(layout::kDatasetJson);
    const DatasetIdentity recorded = DatasetIdentity::from_json(JsonReader(*ds.info.identity, where, "/identity"));
    if (found.sha256 != recorded.sha256) {
      // A record without its file list can say that something changed, not what.
      const std::string diff = recorded.files.empty() ? "dataset.json records no file list to say which file"
                                                      : first_difference(found, recorded).value_or("");
      if (!allow_changed)
        throw InputError(ds.root, "the dataset's files no longer match the identity its dataset.json records (" +
                                      found.sha256 + ", recorded " + recorded.sha256 + "): " + diff +
                                      "; regenerate the dataset, or score it anyway with weathergs evaluate "
                                      "--allow-changed-dataset (recorded in results.json)");
      out.recorded_sha256 = recorded.sha256;
      out.first_difference = diff;
    }
  }
  out.sha256 = found.sha256;
  out.file_count = found.files.size();
  return out;
}

Results evaluate(const EvaluateOptions& o) {
  o.validate();
  const Dataset ds = read_dataset(o.gt_dataset);
  const std::vector<std::string>& views = ds.split(o.split);
  if (views.empty()) throw InputError(ds.file(layout::kDatasetJson) + ":/splits/" + o.split, "split is empty");
  if (!ds.has(o.ground_truth))
    throw InputError(ds.dir(o.ground_truth),
                     std::string("no ") + folder_of(o.ground_truth) +
                         "/ folder: this dataset has no such ground truth (imported real footage has no clean/; "
                         "the targets come from generate --targets)");
  if (!fs::is_directory(o.renders_dir)) throw InputError(o.renders_dir, "renders directory does not exist");

  // Renders must be exactly the split's views.
  std::set<std::string> expected(views.begin(), views.end()), found;
  for (const auto& e : fs::directory_iterator(o.renders_dir))
    if (e.path().extension() == ".png") found.insert(e.path().stem().string());
  std::string missing, extra;
  for (const auto& v : views)
    if (!found.count(v)) missing += (missing.empty() ? "" : ", ") + v;
  for (const auto& v : found)
    if (!expected.count(v)) extra += (extra.empty() ? "" : ", ") + v;
  if (!missing.empty())
    throw InputError(o.renders_dir, "missing renders for " + o.split + " view(s): " + missing);
  if (!extra.empty())
    throw InputError(o.renders_dir, "render(s) for view(s) not in the " + o.split + " split: " + extra);

  Results r;
  r.dataset_identity = identify_dataset(ds, o.allow_changed_dataset);
  r.method = o.method;
  const std::string info_path = (fs::path(o.renders_dir) / "info.json").string();
  if (fs::exists(info_path)) {
    r.method_info = read_json_file(info_path);
    if (!r.method_info.is_object()) throw InputError(info_path, "expected a JSON object");
    if (r.method.empty() && r.method_info.contains("method") && r.method_info["method"].is_string())
      r.method = r.method_info["method"].get<std::string>();
  }
  if (r.method.empty())
    throw InputError(o.renders_dir, "no method name: pass --method NAME or put \"method\" in info.json");
  r.method_info["weathergs_commit"] = source_commit();  // the code that scored (and, in a run, made) it
  r.dataset = ds.info.name;
  r.scene = ds.info.scene;
  r.weather = ds.info.weather;
  r.protocol = scoring_protocol(o);

  std::unique_ptr<Lpips> lpips;
  if (o.scoring.lpips) lpips = std::make_unique<Lpips>(find_lpips_model(o.scoring.lpips_model_search));

  std::vector<std::string> render_paths, gt_paths;
  for (const auto& v : views) {
    render_paths.push_back((fs::path(o.renders_dir) / (v + ".png")).string());
    gt_paths.push_back(ds.path(o.ground_truth, v));
  }
  std::vector<MetricValues> values(views.size());
  ProgressBar bar("evaluate " + r.method, int64_t(views.size()));
  parallel_for(0, int64_t(views.size()), [&](int64_t i) {
    const std::string& v = views[size_t(i)];
    Image render = read_image(render_paths[size_t(i)]);
    Image gt = read_image(gt_paths[size_t(i)]);
    Image mask;
    if (o.mask_dir) mask = read_mask((fs::path(*o.mask_dir) / (v + ".png")).string());
    values[size_t(i)] = score_pair(render, gt, o.scoring, lpips.get(), o.mask_dir ? &mask : nullptr,
                                   "view '" + v + "' (" + render_paths[size_t(i)] + " vs " + gt_paths[size_t(i)] + ")");
    bar.tick();
  });
  bar.finish();
  for (size_t i = 0; i < views.size(); ++i) r.per_view.emplace_back(views[i], values[i]);
  r.metrics = mean_metrics(r.per_view);
  r.sha256_renders = hash_view_files(views, render_paths);
  r.sha256_ground_truth = hash_view_files(views, gt_paths);
  return r;
}

}  // namespace weathergs::evaluator
