#include "evaluator/nerfbaselines.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/error.h"
#include "core/image.h"
#include "core/sha256.h"
#include "evaluator/evaluate.h"

namespace weathergs::evaluator {

namespace fs = std::filesystem;

namespace {

constexpr const char* kProtocol = "default";  // NerfBaselines' name for the protocol we follow
constexpr int kMetricsDecimals = 5;           // serialize_evaluation_results rounds to 5 decimals

std::string base64(const std::string& bytes) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const size_t n = std::min<size_t>(3, bytes.size() - i);
    uint32_t v = 0;
    for (size_t k = 0; k < 3; ++k) v = (v << 8) | (k < n ? uint8_t(bytes[i + k]) : 0u);
    for (size_t k = 0; k < 4; ++k) out += k <= n ? kAlphabet[(v >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

ImageKind ground_truth_kind(const Protocol& p, const std::string& where) {
  if (!p.ground_truth) return ImageKind::kClean;
  for (ImageKind k : {ImageKind::kClean, ImageKind::kImages, ImageKind::kTargetNoParticles, ImageKind::kTargetLensOnly})
    if (*p.ground_truth == folder_of(k)) return k;
  throw InputError(where + ":/protocol/ground_truth", "unknown ground truth folder '" + *p.ground_truth + "'");
}

double rounded(double v) {
  const double scale = std::pow(10.0, kMetricsDecimals);
  return std::round(v * scale) / scale;
}

// An image as scored: RGB, sRGB-encoded, quantized to 8 bits (evaluate.cc's score_pair).
void write_as_scored(const std::string& from, const std::string& to) {
  write_image(to, quantize_uint8(to_srgb(to_rgb(read_image(from)))));
}

}  // namespace

void NerfBaselinesExportOptions::validate() const {
  const std::string where = "nerfbaselines export options";
  if (results.empty()) throw InputError(where, "results is empty: the results.json to export is required");
  if (renders.empty()) throw InputError(where, "renders is empty: the renders folder it scored is required");
  if (dataset.empty()) throw InputError(where, "dataset is empty: the dataset it was scored against is required");
  if (out.empty()) throw InputError(where, "out is empty: the export folder is required");
}

std::string encode_float32_base64(const std::vector<double>& values) {
  std::string bytes;
  for (double v : values) {
    const float f = float(v);
    uint32_t u;
    std::memcpy(&u, &f, 4);
    for (int k = 0; k < 4; ++k) bytes += char((u >> (8 * k)) & 0xff);  // little-endian, like struct "<f"
  }
  return base64(bytes);
}

std::string nerfbaselines_metrics_sha256(const std::map<std::string, std::vector<double>>& metrics_lists) {
  Sha256 h;
  for (const auto& [key, values] : metrics_lists) {  // std::map: sorted keys
    std::string lower = key;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    std::vector<double> sorted = values;
    std::sort(sorted.begin(), sorted.end());
    h.update(lower);
    h.update(encode_float32_base64(sorted));
    h.update("\n");
  }
  return h.hex_digest();
}

NerfBaselinesExport export_nerfbaselines(const NerfBaselinesExportOptions& o) {
  o.validate();
  const Results r = read_results(o.results);
  if (r.protocol.mask)
    throw InputError(o.results, "scored with masked metrics (protocol.mask = " + *r.protocol.mask +
                                    "): NerfBaselines' protocols score whole images");
  if (r.per_view.empty()) throw InputError(o.results, "has no per-view metrics");
  if (fs::exists(o.out) && !o.force) throw InputError(o.out, "already exists: pass --force to replace it");
  const Dataset ds = read_dataset(o.dataset);
  if (ds.info.name != r.dataset)
    throw InputError(o.dataset, "is dataset '" + ds.info.name + "', but " + o.results + " scored '" + r.dataset + "'");
  const ImageKind gt_kind = ground_truth_kind(r.protocol, o.results);

  // The views in NerfBaselines' order (sorted file names), with the files results.json was made from.
  std::vector<std::string> views, render_paths, gt_paths;
  for (const auto& [view, m] : r.per_view) {
    views.push_back(view);
    render_paths.push_back((fs::path(o.renders) / (view + layout::kImageExt)).string());
    gt_paths.push_back(ds.path(gt_kind, view));
  }
  if (!r.sha256_renders.empty() && hash_view_files(views, render_paths) != r.sha256_renders)
    throw InputError(o.renders, "these renders are not the ones " + o.results + " scored (sha256.renders differs)");
  if (!r.sha256_ground_truth.empty() && hash_view_files(views, gt_paths) != r.sha256_ground_truth)
    throw InputError(ds.dir(gt_kind), "this ground truth is not the one " + o.results +
                                          " was scored against (sha256.ground_truth differs)");
  std::vector<size_t> order(views.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) {
    return views[a] + layout::kImageExt < views[b] + layout::kImageExt;
  });

  std::map<std::string, std::vector<double>> lists;
  for (size_t i : order) {
    const MetricValues& m = r.per_view[i].second;
    if (!std::isfinite(m.psnr))
      throw InputError(o.results, "view '" + views[i] + "' has an infinite PSNR (render equals the ground truth): "
                                  "NerfBaselines' results have no infinite values");
    lists["psnr"].push_back(m.psnr);
    lists["ssim"].push_back(m.ssim);
    if (m.lpips) lists["lpips"].push_back(*m.lpips);
  }
  if (!lists["lpips"].empty() && lists["lpips"].size() != order.size())
    throw InputError(o.results, "LPIPS is missing for some views");
  if (lists["lpips"].empty()) lists.erase("lpips");

  AtomicDirectory dir(o.out);
  const fs::path pred = fs::path(dir.path()) / "predictions";
  fs::create_directories(pred / "color");
  fs::create_directories(pred / "gt-color");
  Sha256 pred_sha, gt_sha;
  for (size_t i : order) {
    const std::string file = views[i] + layout::kImageExt;
    const std::string color = (pred / "color" / file).string(), gt = (pred / "gt-color" / file).string();
    write_as_scored(render_paths[i], color);
    write_as_scored(gt_paths[i], gt);
    pred_sha.update(read_file(color));
    gt_sha.update(read_file(gt));
  }

  const Json dataset_metadata{{"name", r.scene},
                              {"scene", r.dataset},
                              {"color_space", "srgb"},
                              {"evaluation_protocol", kProtocol}};
  const Json weathergs_info{{"dataset", r.dataset},
                            {"scene", r.scene},
                            {"weather", r.weather},
                            {"protocol", results_to_json(r)["protocol"]},
                            {"method_info", r.method_info},
                            {"sha256", {{"renders", r.sha256_renders}, {"ground_truth", r.sha256_ground_truth}}}};
  const Json nb_info{{"method", r.method}, {"evaluation_protocol", kProtocol}, {"weathergs", weathergs_info}};
  Json render_info = nb_info;
  render_info["render_dataset_metadata"] = dataset_metadata;
  write_file_atomic((pred / "info.json").string(), render_info.dump(2) + "\n");

  NerfBaselinesExport out;
  Json metrics = Json::object(), raw = Json::object();
  for (const auto& [key, values] : lists) {
    double sum = 0;  // NerfBaselines' default protocol: plain mean over the images
    for (double v : values) sum += v;
    metrics[key] = rounded(sum / double(values.size()));
    raw[key] = encode_float32_base64(values);
  }
  out.results = Json{{"render_dataset_metadata", dataset_metadata},
                     {"nb_info", nb_info},
                     {"metrics", metrics},
                     {"metrics_raw", raw},
                     {"metrics_sha256", nerfbaselines_metrics_sha256(lists)},
                     {"predictions_sha256", pred_sha.hex_digest()},
                     {"ground_truth_sha256", gt_sha.hex_digest()},
                     {"evaluation_protocol", kProtocol}};
  write_file_atomic((fs::path(dir.path()) / "results.json").string(), out.results.dump(2) + "\n");
  dir.commit();
  out.views = int(views.size());
  return out;
}

}  // namespace weathergs::evaluator
