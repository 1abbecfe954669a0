#include "evaluator/results.h"

#include <cmath>
#include <limits>

#include "core/atomic_file.h"

namespace weathergs::evaluator {

std::string Protocol::to_string() const {
  return "ssim=" + ssim + " lpips=" + (lpips ? *lpips : "none") + " quantize_uint8=" +
         (quantize_uint8 ? "true" : "false") + " split=" + split + " mask=" + (mask ? *mask : "none") +
         (mask ? " lpips_mask=" + (lpips_mask ? *lpips_mask : std::string("unmasked")) : std::string());
}

MetricValues mean_metrics(const std::vector<std::pair<std::string, MetricValues>>& per_view) {
  MetricValues m;
  if (per_view.empty()) return m;
  double p = 0, s = 0, l = 0;
  bool all_lpips = true;
  for (const auto& [view, v] : per_view) {
    p += v.psnr;  // +inf propagates, as it should
    s += v.ssim;
    if (v.lpips) l += *v.lpips; else all_lpips = false;
  }
  const double n = double(per_view.size());
  m.psnr = p / n;
  m.ssim = s / n;
  if (all_lpips) m.lpips = l / n;
  return m;
}

Json metrics_to_json(const MetricValues& m) {
  Json j;
  if (std::isinf(m.psnr)) {
    j["psnr"] = nullptr;
    j["psnr_infinite"] = true;
  } else {
    j["psnr"] = m.psnr;
  }
  j["ssim"] = m.ssim;
  j["lpips"] = m.lpips ? Json(*m.lpips) : Json(nullptr);
  return j;
}

namespace {

MetricValues metrics_from_json(const JsonReader& r) {
  if (!r.is_object()) throw InputError(r.where(), "expected an object with psnr, ssim, lpips");
  MetricValues m;
  const bool infinite = r.get_or<bool>("psnr_infinite", false);
  auto psnr = r.get_optional<double>("psnr");
  if (infinite) {
    if (psnr) throw InputError(r.where("psnr"), "must be null when psnr_infinite is true");
    m.psnr = std::numeric_limits<double>::infinity();
  } else {
    if (!psnr) throw InputError(r.where("psnr"), "expected a number (or null with psnr_infinite: true)");
    m.psnr = *psnr;
  }
  m.ssim = r.get<double>("ssim");
  m.lpips = r.get_optional<double>("lpips");
  r.finish();
  return m;
}
}  // namespace

Json results_to_json(const Results& r) {
  Json per_view = Json::object();
  for (const auto& [view, v] : r.per_view) per_view[view] = metrics_to_json(v);
  Json protocol = {{"ssim", r.protocol.ssim},
                   {"lpips", r.protocol.lpips ? Json(*r.protocol.lpips) : Json(nullptr)},
                   {"quantize_uint8", r.protocol.quantize_uint8},
                   {"split", r.protocol.split},
                   {"mask", r.protocol.mask ? Json(*r.protocol.mask) : Json(nullptr)}};
  if (r.protocol.ground_truth) protocol["ground_truth"] = *r.protocol.ground_truth;
  if (r.protocol.lpips_mask) protocol["lpips_mask"] = *r.protocol.lpips_mask;
  Json j = {{"format", "weathergs-results"}, {"version", 1}, {"method", r.method}, {"dataset", r.dataset},
            {"scene", r.scene}, {"weather", r.weather}, {"protocol", protocol},
            {"metrics", metrics_to_json(r.metrics)}, {"per_view", per_view},
            {"method_info", r.method_info},
            {"sha256", {{"renders", r.sha256_renders}, {"ground_truth", r.sha256_ground_truth}}}};
  return j;
}

Results results_from_json(const JsonReader& r) {
  if (!r.is_object()) throw InputError(r.where(), "expected a results object");
  const std::string format = r.get<std::string>("format");
  if (format != "weathergs-results")
    throw InputError(r.where("format"), "expected \"weathergs-results\", got \"" + format + "\"");
  if (int v = r.get<int>("version"); v != 1)
    throw InputError(r.where("version"), "unsupported version " + std::to_string(v) + " (expected 1)");
  Results out;
  out.method = r.get<std::string>("method");
  out.dataset = r.get<std::string>("dataset");
  out.scene = r.get_or<std::string>("scene", "");
  out.weather = r.get_or<std::string>("weather", "");
  JsonReader p = r.child("protocol");
  out.protocol.ssim = p.get<std::string>("ssim");
  out.protocol.lpips = p.get_optional<std::string>("lpips");
  out.protocol.quantize_uint8 = p.get<bool>("quantize_uint8");
  out.protocol.split = p.get<std::string>("split");
  out.protocol.mask = p.get_optional<std::string>("mask");
  out.protocol.ground_truth = p.get_optional<std::string>("ground_truth");
  out.protocol.lpips_mask = p.get_optional<std::string>("lpips_mask");
  if (out.protocol.lpips_mask && *out.protocol.lpips_mask != kLpipsTruthFilled)
    throw InputError(p.where("lpips_mask"), "expected \"" + std::string(kLpipsTruthFilled) + "\", got \"" +
                                                *out.protocol.lpips_mask + "\"");
  p.finish();
  out.metrics = metrics_from_json(r.child("metrics"));
  if (r.has("per_view")) {
    JsonReader pv = r.child("per_view");
    if (!pv.is_object()) throw InputError(pv.where(), "expected an object of view -> metrics");
    for (const std::string& view : pv.keys()) out.per_view.emplace_back(view, metrics_from_json(pv.child(view)));
  }
  if (r.has("method_info")) {
    JsonReader mi = r.child("method_info");
    if (!mi.is_object()) throw InputError(mi.where(), "expected an object");
    out.method_info = mi.value();
  }
  if (r.has("sha256")) {
    JsonReader s = r.child("sha256");
    out.sha256_renders = s.get_or<std::string>("renders", "");
    out.sha256_ground_truth = s.get_or<std::string>("ground_truth", "");
    s.finish();
  }
  r.finish();
  return out;
}

Results read_results(const std::string& path) { return results_from_json(JsonReader::from_file(path)); }

void write_results(const std::string& path, const Results& r) {
  write_file_atomic(path, results_to_json(r).dump(2) + "\n");
}

std::string format_metric(double v, int decimals) {
  if (std::isinf(v)) return v > 0 ? "+inf" : "-inf";
  if (std::isnan(v)) return "nan";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace weathergs::evaluator
