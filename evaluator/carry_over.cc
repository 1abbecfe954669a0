#include "evaluator/carry_over.h"

#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "core/error.h"
#include "evaluator/archive.h"
#include "evaluator/leaderboard.h"
#include "evaluator/statistics.h"

namespace weathergs::evaluator {

namespace {

// variant -> method -> seed -> metrics
using SuiteMetrics = std::map<std::string, std::map<std::string, std::map<int, MetricValues>>>;

SuiteMetrics read_suite(const std::string& dir, int* runs) {
  const std::vector<ArchivedRun> archived = read_archive(dir);
  if (archived.empty())
    throw InputError(dir, "holds no archived run (expected <variant>/<method>/seed<N>/results.json, docs/archive.md)");
  // One suite is read as one leaderboard: its runs must agree on recipes and datasets.
  std::vector<LoadedResults> loaded;
  for (const ArchivedRun& r : archived) loaded.push_back({r.dir + "/" + kArchiveResultsFile, r.results});
  find_mixed_data(loaded, {});
  find_mixed_recipes(loaded, {});
  SuiteMetrics m;
  for (const ArchivedRun& r : archived) m[r.cell.variant][r.cell.method][r.cell.seed] = r.results.metrics;
  *runs = int(archived.size());
  return m;
}

double metric_of(const MetricValues& m, const std::string& metric) {
  if (metric == "psnr") return m.psnr;
  if (metric == "ssim") return m.ssim;
  return m.lpips ? *m.lpips : std::nan("");
}

// The mean over the seeds where both methods ran of (a - b); NaN where there is none or a value is
// not finite (an infinite PSNR, a skipped LPIPS).
double paired(const SuiteMetrics& s, const std::string& variant, const CarryOverPair& p, const std::string& metric,
              int* seeds) {
  *seeds = 0;
  const auto v = s.find(variant);
  if (v == s.end() || !v->second.count(p.a) || !v->second.count(p.b)) return std::nan("");
  const auto& a = v->second.at(p.a);
  const auto& b = v->second.at(p.b);
  double sum = 0;
  for (const auto& [seed, ma] : a) {
    const auto mb = b.find(seed);
    if (mb == b.end()) continue;
    const double d = metric_of(ma, metric) - metric_of(mb->second, metric);
    if (!std::isfinite(d)) return std::nan("");
    sum += d;
    ++*seeds;
  }
  return *seeds ? sum / *seeds : std::nan("");
}

std::string num(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::string verdict(const CarryOverRow& r) {
  const int n = int(r.to.size());
  if (r.from_mean == 0) return "no sign to carry (the source's mean difference is 0)";
  const std::string count = std::to_string(r.agree) + " of " + std::to_string(n);
  if (r.p < kCarryOverAlpha) return "holds: same sign on " + count;
  if (sign_test_p(n, n) >= kCarryOverAlpha)
    return std::string(2 * r.agree > n ? "same sign" : "sign not kept") + " on " + count +
           ", too few variants for the test (all " + std::to_string(n) + " agreeing gives p = " +
           num("%.3f", sign_test_p(n, n)) + ")";
  if (2 * r.agree > n) return "same sign on " + count + ", not significant";
  return "does not hold: same sign on " + count;
}

}  // namespace

std::vector<CarryOverPair> parse_carry_over_pairs(const std::string& text, const std::string& flag) {
  std::vector<CarryOverPair> pairs;
  std::stringstream in(text);
  std::string entry;
  while (std::getline(in, entry, ',')) {
    const size_t colon = entry.find(':');
    if (colon == std::string::npos || colon == 0 || colon + 1 == entry.size() || entry.find(':', colon + 1) != std::string::npos)
      throw InputError(flag, "'" + entry + "': expected METHOD_A:METHOD_B (the difference A - B), e.g. weathergs:3dgs");
    pairs.push_back({entry.substr(0, colon), entry.substr(colon + 1)});
    if (pairs.back().a == pairs.back().b) throw InputError(flag, "'" + entry + "': a method against itself");
  }
  if (pairs.empty()) throw InputError(flag, "no pair given (expected METHOD_A:METHOD_B[,...])");
  return pairs;
}

CarryOver carry_over(const std::string& from_dir, const std::string& to_dir, const std::vector<CarryOverPair>& pairs) {
  CarryOver c;
  c.from_dir = from_dir;
  c.to_dir = to_dir;
  const SuiteMetrics from = read_suite(from_dir, &c.from_runs);
  const SuiteMetrics to = read_suite(to_dir, &c.to_runs);
  for (const CarryOverPair& p : pairs) {
    bool any = false;
    for (const char* metric : {"psnr", "ssim", "lpips"}) {
      CarryOverRow r;
      r.pair = p;
      r.metric = metric;
      for (const auto& [variant, methods] : to) {
        int nf = 0, nt = 0;
        const double df = paired(from, variant, p, metric, &nf), dt = paired(to, variant, p, metric, &nt);
        if (std::isnan(df) || std::isnan(dt)) continue;
        r.variants.push_back(variant);
        r.from.push_back(df);
        r.to.push_back(dt);
        r.from_seeds.push_back(nf);
        r.to_seeds.push_back(nt);
      }
      if (r.variants.empty()) continue;
      any = true;
      const double n = double(r.variants.size());
      for (size_t i = 0; i < r.from.size(); ++i) {
        r.from_mean += r.from[i] / n;
        r.to_mean += r.to[i] / n;
      }
      for (double d : r.to) r.agree += (d > 0 && r.from_mean > 0) || (d < 0 && r.from_mean < 0);
      r.p = sign_test_p(r.agree, int(r.to.size()));
      r.verdict = verdict(r);
      c.rows.push_back(std::move(r));
    }
    if (!any)
      c.notes.push_back(p.a + " - " + p.b + ": no variant where both suites ran both methods at a common seed");
  }
  return c;
}

std::string render_carry_over(const CarryOver& c) {
  std::ostringstream o;
  auto runs = [](int n) { return std::to_string(n) + (n == 1 ? " run" : " runs"); };
  o << "From `" << c.from_dir << "` (" << runs(c.from_runs) << ") to `" << c.to_dir << "` (" << runs(c.to_runs)
    << "). Per variant, a difference is the mean over the seeds where both methods ran of (A - B); the sign "
       "test counts the target's variants whose difference has the sign of the source's mean (one-sided, p = "
       "P(X >= k), X ~ Binomial(n, 1/2), holds at p < "
    << num("%.2f", kCarryOverAlpha) << "); size = target mean / source mean.\n\n";
  if (c.rows.empty())
    o << "No paired difference has both methods in both suites yet.\n";
  else
    o << "| A - B | metric | variants | source mean | target mean | size | same sign | p | verdict |\n"
         "|---|---|---|---|---|---|---|---|---|\n";
  for (const CarryOverRow& r : c.rows) {
    const bool psnr = r.metric == "psnr";
    const char* f = psnr ? "%+.2f dB" : "%+.4f";
    o << "| " << r.pair.a << " - " << r.pair.b << " | " << (psnr ? "PSNR" : r.metric == "ssim" ? "SSIM" : "LPIPS")
      << " | " << r.variants.size() << " | " << num(f, r.from_mean) << " | " << num(f, r.to_mean) << " | "
      << (r.from_mean != 0 ? num("%.2f", r.to_mean / r.from_mean) : "n/a") << " | " << r.agree << " of "
      << r.to.size() << " | " << num("%.3f", r.p) << " | " << r.verdict << " |\n";
  }
  for (const std::string& n : c.notes) o << "\n- " << n;
  if (!c.notes.empty()) o << "\n";
  std::set<std::string> shown;
  for (const CarryOverRow& r : c.rows) {
    const std::string name = r.pair.a + " - " + r.pair.b;
    if (r.metric != "psnr" || !shown.insert(name).second) continue;
    o << "\n" << name << ", PSNR (dB) per variant (seeds averaged in brackets):\n\n";
    o << "| variant | source | target |\n|---|---|---|\n";
    for (size_t i = 0; i < r.variants.size(); ++i)
      o << "| " << r.variants[i] << " | " << num("%+.2f", r.from[i]) << " (" << r.from_seeds[i] << ") | "
        << num("%+.2f", r.to[i]) << " (" << r.to_seeds[i] << ") |\n";
  }
  return o.str();
}

}  // namespace weathergs::evaluator
