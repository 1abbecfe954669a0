#include "evaluator/check.h"

#include <cmath>
#include <map>
#include <sstream>

namespace weathergs::evaluator {

void CheckTolerances::validate() const {
  for (auto [name, v] : {std::pair<const char*, double>{"psnr", psnr}, {"ssim", ssim}, {"lpips", lpips}})
    if (!(std::isfinite(v) && v >= 0))
      throw InputError("check tolerances", std::string(name) + " is " + std::to_string(v) + ", must be a finite number >= 0");
  for (auto [name, v] : {std::pair<const char*, std::optional<double>>{"per_view.psnr", view_psnr},
                         {"per_view.ssim", view_ssim}, {"per_view.lpips", view_lpips}})
    if (v && !(std::isfinite(*v) && *v >= 0))
      throw InputError("check tolerances", std::string(name) + " is " + std::to_string(*v) + ", must be a finite number >= 0");
}

CheckTolerances CheckTolerances::from_file(const std::string& path) {
  JsonReader r = JsonReader::from_file(path);
  CheckTolerances t;
  t.psnr = r.get_or<double>("psnr", t.psnr);
  t.ssim = r.get_or<double>("ssim", t.ssim);
  t.lpips = r.get_or<double>("lpips", t.lpips);
  if (r.has("per_view")) {
    JsonReader v = r.child("per_view");
    if (v.has("psnr")) t.view_psnr = v.get<double>("psnr");
    if (v.has("ssim")) t.view_ssim = v.get<double>("ssim");
    if (v.has("lpips")) t.view_lpips = v.get<double>("lpips");
    v.finish();
  }
  r.get_or<std::string>("basis", "");
  r.finish();
  try {
    t.validate();
  } catch (const InputError& e) {
    throw InputError(path, e.problem());
  }
  return t;
}

namespace {

std::map<std::string, const LoadedResults*> by_dataset(const std::vector<LoadedResults>& rs, const char* side) {
  std::map<std::string, const LoadedResults*> m;
  for (const auto& r : rs) {
    auto [it, inserted] = m.emplace(r.results.dataset, &r);
    if (!inserted)
      throw InputError(r.path, std::string("dataset '") + r.results.dataset + "' appears twice among the " + side +
                                   " results (also in " + it->second->path + "); give one result per dataset");
  }
  return m;
}

std::string pad(const std::string& s, size_t n) { return s.size() >= n ? s : s + std::string(n - s.size(), ' '); }
std::string lpad(const std::string& s, size_t n) { return s.size() >= n ? s : std::string(n - s.size(), ' ') + s; }

std::string signed_delta(double d, int decimals) {
  if (std::isnan(d)) return "n/a";
  std::string s = format_metric(d, decimals);
  return (d >= 0 && s[0] != '+' ? "+" : "") + s;
}

// What the baseline records of how it was made, compared key by key: a key the baseline has must
// be equal in the new result. Returns the first difference, "" when none.
std::string provenance_mismatch(const Json& base_info, const Json& new_info, const std::vector<const char*>& keys) {
  for (const char* k : keys) {
    if (!base_info.contains(k)) continue;
    const Json n = new_info.contains(k) ? new_info.at(k) : Json();
    if (n != base_info.at(k))
      return std::string("method_info.") + k + " is " + (n.is_null() ? std::string("missing") : n.dump()) +
             ", the baseline's " + base_info.at(k).dump();
  }
  return "";
}

struct MetricRow {
  const char* name;
  std::optional<double> b, n;
  double tol;
  bool higher_better;
  int decimals;
};

std::vector<MetricRow> metric_rows(const MetricValues& b, const MetricValues& n, double tp, double ts, double tl) {
  return {{"PSNR", b.psnr, n.psnr, tp, true, 3}, {"SSIM", b.ssim, n.ssim, ts, true, 4}, {"LPIPS", b.lpips, n.lpips, tl, false, 4}};
}

// The verdict of one row: "" when within tolerance (or skipped on both sides), else why not.
// *change is new - baseline (NaN when a side is missing).
std::string row_failure(const MetricRow& r, double* change) {
  *change = NAN;
  if (!r.b && !r.n) return "";  // LPIPS skipped on both sides (same protocol)
  if (!r.b || !r.n) return "missing";
  const double bv = *r.b, nv = *r.n;
  // Worse by: a drop for PSNR/SSIM, a rise for LPIPS. inf - inf counts as no change.
  const double worse = (bv == nv) ? 0.0 : (r.higher_better ? bv - nv : nv - bv);
  *change = (bv == nv) ? 0.0 : nv - bv;
  return (std::isnan(worse) || worse > r.tol) ? "worse" : "";
}

}  // namespace

CheckReport check_regression(const std::vector<LoadedResults>& baseline, const std::vector<LoadedResults>& current,
                             const CheckOptions& options) {
  const CheckTolerances& tol = options.tolerances;
  tol.validate();
  if (baseline.empty()) throw InputError("baseline", "no baseline results given");
  if (current.empty()) throw InputError("results", "no results given");
  const auto base = by_dataset(baseline, "baseline");
  const auto cur = by_dataset(current, "new");
  const double vp = tol.per_view(tol.psnr, tol.view_psnr), vs = tol.per_view(tol.ssim, tol.view_ssim),
               vl = tol.per_view(tol.lpips, tol.view_lpips);

  CheckReport report;
  report.json = {{"passed", true},
                 {"tolerances", {{"psnr", tol.psnr}, {"ssim", tol.ssim}, {"lpips", tol.lpips},
                                 {"per_view", {{"psnr", vp}, {"ssim", vs}, {"lpips", vl}}}}},
                 {"datasets", Json::array()}};
  std::ostringstream o;
  o << "Regression check (tolerances: PSNR " << tol.psnr << " dB, SSIM " << tol.ssim << ", LPIPS " << tol.lpips
    << "; per view " << vp << " dB, " << vs << ", " << vl << ")\n";
  int failures = 0;
  for (const auto& [dataset, b] : base) {
    Json dj = {{"dataset", dataset}, {"baseline", b->path}, {"metrics", Json::array()}, {"failed_views", Json::array()}};
    o << "\n" << dataset << "  (baseline " << b->path;
    auto it = cur.find(dataset);
    if (it == cur.end()) {
      o << ")\n  FAIL  no new result for this dataset\n";
      dj["status"] = "missing";
      report.json["datasets"].push_back(dj);
      ++failures;
      continue;
    }
    const Results& br = b->results;
    const Results& nr = it->second->results;
    const std::string& np = it->second->path;
    o << ", new " << np << ")\n";
    dj["results"] = np;
    if (!(br.protocol == nr.protocol))
      throw InputError(np, "protocol differs from baseline " + b->path + " (" + nr.protocol.to_string() + " vs " +
                               br.protocol.to_string() + "): not comparable");
    if (!br.sha256_ground_truth.empty() && br.sha256_ground_truth != nr.sha256_ground_truth)
      throw InputError(np, "sha256.ground_truth " + (nr.sha256_ground_truth.empty() ? "is missing" : nr.sha256_ground_truth) +
                               " differs from the baseline's " + br.sha256_ground_truth + " (" + b->path +
                               "): the ground truth itself changed, so the scores are not comparable; regenerate the "
                               "baseline (benchmarks/baselines/README.md) if the change is intended");
    if (br.dataset_identity && dataset_identity_differs(br, nr)) {
      const std::string why = "dataset_identity.sha256 is " + dataset_identity_text(nr) + ", the baseline's " +
                              dataset_identity_text(br);
      if (!options.allow_other_data)
        throw InputError(np, "scored on other data than the baseline " + b->path + ": " + why +
                                 "; pass --allow-other-data to compare anyway, or regenerate the baseline");
      o << "  note: other data than the baseline (allowed): " << why << "\n";
      dj["other_data"] = true;
    } else if (!br.dataset_identity && nr.dataset_identity) {
      o << "  note: the baseline records no dataset identity, so the data are not compared\n";
    }
    if (std::string why = provenance_mismatch(br.method_info, nr.method_info, {"weights"}); !why.empty()) {
      if (!options.allow_other_weights)
        throw InputError(np, "made with other weights than the baseline " + b->path + ": " + why +
                                 "; pass --allow-other-weights to compare anyway, or regenerate the baseline");
      o << "  note: other weights than the baseline (allowed): " << why << "\n";
    }
    // schedule_length beside iterations: a run shortened from another schedule length is another form.
    if (std::string why = provenance_mismatch(
            br.method_info, nr.method_info, {"method", "method_description", "iterations", "schedule", "schedule_length"});
        !why.empty()) {
      if (!options.allow_other_recipe)
        throw InputError(np, "made with another recipe than the baseline " + b->path + ": " + why +
                                 "; pass --allow-other-recipe to compare anyway, or regenerate the baseline");
      o << "  note: another recipe than the baseline (allowed): " << why << "\n";
    }
    if (br.method != nr.method) o << "  note: method '" << nr.method << "' vs baseline '" << br.method << "'\n";
    o << "  " << pad("metric", 7) << lpad("baseline", 10) << lpad("new", 10) << lpad("change", 10) << lpad("allowed", 10) << "  verdict\n";
    bool ok = true;
    for (const MetricRow& r : metric_rows(br.metrics, nr.metrics, tol.psnr, tol.ssim, tol.lpips)) {
      if (!r.b && !r.n) continue;
      double change;
      const std::string why = row_failure(r, &change);
      const bool fail = !why.empty();
      const std::string verdict = why == "missing" ? "FAIL (missing)" : fail ? "FAIL" : (change * (r.higher_better ? 1 : -1) > 0 ? "ok (better)" : "ok");
      o << "  " << pad(r.name, 7) << lpad(r.b ? format_metric(*r.b, r.decimals) : "-", 10)
        << lpad(r.n ? format_metric(*r.n, r.decimals) : "-", 10) << lpad(signed_delta(change, r.decimals), 10)
        << lpad((r.higher_better ? "-" : "+") + format_metric(r.tol, r.decimals), 10) << "  " << verdict << "\n";
      Json mj = {{"metric", r.name}, {"baseline", r.b && std::isfinite(*r.b) ? Json(*r.b) : Json(nullptr)},
                 {"new", r.n && std::isfinite(*r.n) ? Json(*r.n) : Json(nullptr)}, {"passed", !fail}};
      dj["metrics"].push_back(mj);
      ok = ok && !fail;
    }
    // Every view the baseline scored, with the per-view tolerances.
    std::map<std::string, const MetricValues*> new_views;
    for (const auto& [v, m] : nr.per_view) new_views[v] = &m;
    int view_failures = 0;
    for (const auto& [v, bm] : br.per_view) {
      auto nv = new_views.find(v);
      if (nv == new_views.end()) {
        o << "  FAIL  view " << v << ": no new score\n";
        dj["failed_views"].push_back({{"view", v}, {"metric", "all"}, {"why", "missing"}});
        ++view_failures;
        continue;
      }
      for (const MetricRow& r : metric_rows(bm, *nv->second, vp, vs, vl)) {
        double change;
        const std::string why = row_failure(r, &change);
        if (why.empty()) continue;
        o << "  FAIL  view " << v << " " << r.name << ": " << (r.b ? format_metric(*r.b, r.decimals) : "-") << " -> "
          << (r.n ? format_metric(*r.n, r.decimals) : "-") << " (" << signed_delta(change, r.decimals) << ", allowed "
          << (r.higher_better ? "-" : "+") << format_metric(r.tol, r.decimals) << ")\n";
        dj["failed_views"].push_back({{"view", v}, {"metric", r.name}, {"why", why}});
        ++view_failures;
      }
    }
    if (!br.per_view.empty())
      o << "  per view: " << (view_failures == 0 ? "every one" : "not every one") << " of the baseline's "
        << br.per_view.size() << " views within the per-view tolerances\n";
    ok = ok && view_failures == 0;
    dj["status"] = ok ? "passed" : "failed";
    report.json["datasets"].push_back(dj);
    if (!ok) ++failures;
  }
  for (const auto& [dataset, n] : cur)
    if (!base.count(dataset)) o << "\nnote: " << dataset << " (" << n->path << ") has no baseline; not checked\n";
  report.passed = failures == 0;
  report.json["passed"] = report.passed;
  o << "\n" << (report.passed ? "PASSED" : "FAILED") << ": " << base.size() - size_t(failures) << " of " << base.size()
    << " dataset(s) within tolerance\n";
  report.text = o.str();
  return report;
}

}  // namespace weathergs::evaluator
