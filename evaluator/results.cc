#include "evaluator/results.h"

#include <cmath>
#include <limits>

#include "core/atomic_file.h"
#include "core/json_fields.h"

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

namespace {
// The scoring protocol a results.json records (DATASET_FORMAT.md). The optional entries may be absent or
// null; lpips and mask are written as null when unset, as the format has always had them.
constexpr auto kProtocolFields = [](auto& s, auto& f) {
  f("ssim", s.ssim);
  f("lpips", s.lpips, json_fields::WriteNull{});
  f("quantize_uint8", s.quantize_uint8);
  f("split", s.split);
  f("mask", s.mask, json_fields::WriteNull{});
  f("ground_truth", s.ground_truth);
  f("lpips_mask", s.lpips_mask);
};
}  // namespace

namespace {
// A perfect score's PSNR is infinite, which JSON cannot hold: it is written as null with
// "psnr_infinite": true (listed first, so that reading psnr knows).
constexpr auto kMetricFields = [](auto& m, auto& f) {
  f.custom(
      "psnr_infinite", [&] { return std::isinf(m.psnr) ? Json(true) : Json(Json::value_t::discarded); },
      [&](const JsonReader& r, const std::string& k) {
        if (r.get_or<bool>(k, false)) m.psnr = std::numeric_limits<double>::infinity();
      });
  f.custom(
      "psnr", [&] { return std::isinf(m.psnr) ? Json(nullptr) : Json(m.psnr); },
      [&](const JsonReader& r, const std::string& k) {
        const std::optional<double> psnr = r.get_optional<double>(k);
        if (std::isinf(m.psnr)) {
          if (psnr) throw InputError(r.where(k), "must be null when psnr_infinite is true");
        } else {
          if (!psnr) throw InputError(r.where(k), "expected a number (or null with psnr_infinite: true)");
          m.psnr = *psnr;
        }
      });
  f("ssim", m.ssim);
  f("lpips", m.lpips, json_fields::WriteNull{});
};

MetricValues metrics_from_json(const JsonReader& r) {
  if (!r.is_object()) throw InputError(r.where(), "expected an object with psnr, ssim, lpips");
  return json_fields::read(r, MetricValues{}, kMetricFields, json_fields::Absent::kError);
}
}  // namespace

Json metrics_to_json(const MetricValues& m) { return json_fields::write(m, kMetricFields); }

namespace {
constexpr const char* kDiffersFromRecorded = "differs_from_recorded";

Json scored_dataset_to_json(const ScoredDataset& d) {
  Json j = {{"scheme", DatasetIdentity::kScheme}, {"sha256", d.sha256}, {"file_count", d.file_count}};
  if (d.recorded_sha256)
    j[kDiffersFromRecorded] = {{"sha256", *d.recorded_sha256}, {"first_difference", d.first_difference.value_or("")}};
  return j;
}

ScoredDataset scored_dataset_from_json(const JsonReader& r) {
  if (!r.is_object()) throw InputError(r.where(), "expected a dataset identity {scheme, sha256, file_count}");
  ScoredDataset d;
  if (r.has(kDiffersFromRecorded)) {  // read first: DatasetIdentity::from_json refuses keys it does not know
    const JsonReader c = r.child(kDiffersFromRecorded);
    d.recorded_sha256 = c.get<std::string>("sha256");
    d.first_difference = c.get<std::string>("first_difference");
    c.finish();
  }
  d.file_count = r.get<size_t>("file_count");
  if (r.has("files")) throw InputError(r.where("files"), "results record the identity without its files");
  d.sha256 = DatasetIdentity::from_json(r).sha256;  // checks the scheme and the hash's form
  return d;
}
}  // namespace

bool dataset_identity_differs(const Results& a, const Results& b) {
  if (!a.dataset_identity || !b.dataset_identity) return a.dataset_identity.has_value() != b.dataset_identity.has_value();
  return a.dataset_identity->sha256 != b.dataset_identity->sha256;
}

std::string short_dataset_identity(const Results& r) {
  return r.dataset_identity ? r.dataset_identity->sha256.substr(0, 12) : "unknown";
}

std::string dataset_identity_text(const Results& r) {
  return r.dataset_identity ? r.dataset_identity->sha256 : "none recorded";
}

Json protocol_to_json(const Protocol& p) { return json_fields::write(p, kProtocolFields); }

Json results_to_json(const Results& r) {
  Json per_view = Json::object();
  for (const auto& [view, v] : r.per_view) per_view[view] = metrics_to_json(v);
  const Json protocol = protocol_to_json(r.protocol);
  Json j = {{"format", "weathergs-results"}, {"version", 1}, {"method", r.method}, {"dataset", r.dataset},
            {"scene", r.scene}, {"weather", r.weather}, {"protocol", protocol},
            {"metrics", metrics_to_json(r.metrics)}, {"per_view", per_view},
            {"method_info", r.method_info},
            {"sha256", {{"renders", r.sha256_renders}, {"ground_truth", r.sha256_ground_truth}}}};
  if (r.dataset_identity) j["dataset_identity"] = scored_dataset_to_json(*r.dataset_identity);
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
  out.protocol = json_fields::read(p, Protocol{}, kProtocolFields, json_fields::Absent::kError);
  if (out.protocol.lpips_mask && *out.protocol.lpips_mask != kLpipsTruthFilled)
    throw InputError(p.where("lpips_mask"), "expected \"" + std::string(kLpipsTruthFilled) + "\", got \"" +
                                                *out.protocol.lpips_mask + "\"");
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
  if (r.has("dataset_identity")) out.dataset_identity = scored_dataset_from_json(r.child("dataset_identity"));
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
