#include "evaluator/check.h"

#include <cmath>
#include <map>
#include <sstream>

namespace weathergs::evaluator {

void CheckTolerances::validate() const {
  for (auto [name, v] : {std::pair<const char*, double>{"psnr", psnr}, {"ssim", ssim}, {"lpips", lpips}})
    if (!(std::isfinite(v) && v >= 0))
      throw InputError("check tolerances", std::string(name) + " is " + std::to_string(v) + ", must be a finite number >= 0");
}

CheckTolerances CheckTolerances::from_file(const std::string& path) {
  JsonReader r = JsonReader::from_file(path);
  CheckTolerances t;
  t.psnr = r.get_or<double>("psnr", t.psnr);
  t.ssim = r.get_or<double>("ssim", t.ssim);
  t.lpips = r.get_or<double>("lpips", t.lpips);
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

}  // namespace

CheckReport check_regression(const std::vector<LoadedResults>& baseline, const std::vector<LoadedResults>& current,
                             const CheckTolerances& tol) {
  tol.validate();
  if (baseline.empty()) throw InputError("baseline", "no baseline results given");
  if (current.empty()) throw InputError("results", "no results given");
  const auto base = by_dataset(baseline, "baseline");
  const auto cur = by_dataset(current, "new");

  CheckReport report;
  report.json = {{"passed", true}, {"tolerances", {{"psnr", tol.psnr}, {"ssim", tol.ssim}, {"lpips", tol.lpips}}},
                 {"datasets", Json::array()}};
  std::ostringstream o;
  o << "Regression check (tolerances: PSNR " << tol.psnr << " dB, SSIM " << tol.ssim << ", LPIPS " << tol.lpips << ")\n";
  int failures = 0;
  for (const auto& [dataset, b] : base) {
    Json dj = {{"dataset", dataset}, {"baseline", b->path}, {"metrics", Json::array()}};
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
    o << ", new " << it->second->path << ")\n";
    dj["results"] = it->second->path;
    if (!(br.protocol == nr.protocol))
      throw InputError(it->second->path, "protocol differs from baseline " + b->path + " (" + nr.protocol.to_string() +
                                             " vs " + br.protocol.to_string() + "): not comparable");
    if (br.method != nr.method) o << "  note: method '" << nr.method << "' vs baseline '" << br.method << "'\n";
    o << "  " << pad("metric", 7) << lpad("baseline", 10) << lpad("new", 10) << lpad("change", 10) << lpad("allowed", 10) << "  verdict\n";
    struct Row { const char* name; std::optional<double> b, n; double tol; bool higher_better; int decimals; };
    const Row rows[3] = {{"PSNR", br.metrics.psnr, nr.metrics.psnr, tol.psnr, true, 3},
                         {"SSIM", br.metrics.ssim, nr.metrics.ssim, tol.ssim, true, 4},
                         {"LPIPS", br.metrics.lpips, nr.metrics.lpips, tol.lpips, false, 4}};
    bool ok = true;
    for (const Row& r : rows) {
      std::string verdict;
      double change = NAN;
      bool fail = false;
      if (!r.b && !r.n) continue;  // LPIPS skipped on both sides (same protocol)
      if (!r.b || !r.n) {
        verdict = "FAIL (missing)";
        fail = true;
      } else {
        const double bv = *r.b, nv = *r.n;
        // Worse by: a drop for PSNR/SSIM, a rise for LPIPS. inf - inf counts as no change.
        double worse = (bv == nv) ? 0.0 : (r.higher_better ? bv - nv : nv - bv);
        change = (bv == nv) ? 0.0 : nv - bv;
        fail = std::isnan(worse) || worse > r.tol;
        verdict = fail ? "FAIL" : (worse < 0 ? "ok (better)" : "ok");
      }
      o << "  " << pad(r.name, 7) << lpad(r.b ? format_metric(*r.b, r.decimals) : "-", 10)
        << lpad(r.n ? format_metric(*r.n, r.decimals) : "-", 10) << lpad(signed_delta(change, r.decimals), 10)
        << lpad((r.higher_better ? "-" : "+") + format_metric(r.tol, r.decimals), 10) << "  " << verdict << "\n";
      Json mj = {{"metric", r.name}, {"baseline", r.b && std::isfinite(*r.b) ? Json(*r.b) : Json(nullptr)},
                 {"new", r.n && std::isfinite(*r.n) ? Json(*r.n) : Json(nullptr)}, {"passed", !fail}};
      dj["metrics"].push_back(mj);
      ok = ok && !fail;
    }
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
