#include "evaluator/paper_agreement.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "core/json_reader.h"
#include "evaluator/statistics.h"

namespace weathergs::evaluator {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// `more`: the object has further keys, read by the caller.
PublishedMetrics read_metrics(const JsonReader& r, bool more = false) {
  PublishedMetrics m;
  m.psnr = r.get_number("psnr", 0, 100);
  m.ssim = r.get_number("ssim", -1, 1);
  m.lpips = r.get_number("lpips", 0, 2);
  if (!more) r.finish();
  return m;
}

// "~395 min", "32.3 s", "7.8 GB": the number, in the unit `unit` (min, s or GB).
double read_quantity(const JsonReader& r, const std::string& key, const std::string& unit) {
  const std::string text = r.get<std::string>(key);
  std::istringstream in(text[0] == '~' ? text.substr(1) : text);
  double v = 0;
  std::string u;
  in >> v >> u;
  struct Unit { const char* name; const char* base; double factor; };
  for (const Unit& c : {Unit{"min", "min", 1}, Unit{"h", "min", 60}, Unit{"s", "min", 1.0 / 60}, Unit{"s", "s", 1},
                        Unit{"ms", "s", 1e-3}, Unit{"GB", "GB", 1}, Unit{"MB", "GB", 1.0 / 1024}})
    if (in && u == c.name && unit == c.base && v > 0) return v * c.factor;
  throw InputError(r.where(key), "expected a positive quantity in " + unit + " (e.g. \"~28 min\", \"0.02 s\", \"1.1 GB\"), got \"" + text + "\"");
}

std::string our_name(const std::map<std::string, std::string>& names, const JsonReader& r, const std::string& paper_name) {
  const auto it = names.find(paper_name);
  if (it == names.end()) throw InputError(r.where(paper_name), "a method missing from method_names");
  return it->second;
}

}  // namespace

PublishedTables read_published_tables(const std::string& path) {
  const JsonReader r = JsonReader::from_file(path);
  if (!r.is_object()) throw InputError(r.where(), "expected the paper's tables as an object");
  PublishedTables p;
  p.source = r.get<std::string>("source");
  r.get<std::string>("notes");
  r.mark("readings");  // the paper's own words; this file's checks are below
  std::map<std::string, std::string> names;
  const JsonReader n = r.child("method_names");
  for (const std::string& k : n.keys()) names[k] = n.get<std::string>(k);
  n.finish();
  for (const auto& [key, weather] : {std::pair<const char*, const char*>{"table_1_snow", "snow"}, {"table_2_rain", "rain"}}) {
    const JsonReader t = r.child(key);
    for (const std::string& method : t.keys()) {
      const JsonReader row = t.child(method);
      for (const std::string& scene : row.keys())
        if (scene != "average") read_metrics(row.child(scene));
      p.averages[weather][our_name(names, t, method)] = read_metrics(row.child("average"));
      if (std::string(weather) == "snow") p.shared_methods.push_back(our_name(names, t, method));
      row.finish();
    }
    t.finish();
  }
  const JsonReader a = r.child("table_3_ablation");
  for (const std::string& method : a.keys()) p.ablation[our_name(names, a, method)] = read_metrics(a.child(method));
  a.finish();
  const JsonReader b = r.child("table_4_backends");
  const JsonReader nerf = b.child("Ours-NeRF"), gs = b.child("Ours-3DGS");
  for (const JsonReader* x : {&nerf, &gs}) {
    read_metrics(*x, true);
    (x == &nerf ? p.nerf_train_min : p.gs_train_min) = read_quantity(*x, "training", "min");
    (x == &nerf ? p.nerf_render_s : p.gs_render_s) = read_quantity(*x, "render_per_view", "s");
    (x == &nerf ? p.nerf_memory_gb : p.gs_memory_gb) = read_quantity(*x, "gpu_memory", "GB");
    x->finish();
  }
  b.finish();
  r.finish();
  for (const char* w : {"snow", "rain"})
    for (const std::string& m : p.shared_methods)
      if (!p.averages[w].count(m)) throw InputError(path, "table of " + std::string(w) + " lacks " + m);
  return p;
}

namespace {

std::string fmt(double v, int decimals, bool sign = false) {
  if (!std::isfinite(v)) return "–";
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(decimals);
  o << (sign && v >= 0 ? "+" : "") << v;
  return o.str();
}

// The paper's weather a table of ours stands for: its particles ("rain+lens_droplets" is the paper's
// rain, which had drops on the lens too); "" for any other.
std::string paper_weather(const std::string& ours) {
  for (const char* w : {"snow", "rain"})
    if (ours.compare(0, std::string(w).size(), w) == 0) return w;
  return "";
}

// Our average of `method` in the table of the paper's `weather` (metric 0 psnr, 2 lpips), NaN when absent.
double our_average(const PaperTables& t, const std::string& weather, const std::string& method, int metric) {
  for (const auto& q : t.quality) {
    if (paper_weather(q.weather) != weather) continue;
    for (size_t m = 0; m < q.methods.size(); ++m) {
      const CellStats& c = q.average[m];
      if (q.methods[m] != method || c.n == 0 || (metric == 2 && !c.has_lpips)) continue;
      return metric == 0 ? c.psnr : c.lpips;
    }
  }
  return kNaN;
}

const PairedDifference* our_difference(const PaperTables& t, const std::string& method, const std::string& baseline,
                                       const std::string& weather) {
  for (const auto& d : t.differences)
    if (d.method == method && d.baseline == baseline && (d.weather == "all" ? "all" : paper_weather(d.weather)) == weather)
      return &d;
  return nullptr;
}

struct Row {
  std::string reading, paper, ours, verdict;
};

// Two methods' mean PSNR over the variants (the quality tables' cells, each a mean over seeds) that
// both ran; variants == 0 when none.
struct BothRan {
  double a = kNaN, b = kNaN;
  int variants = 0;
};
BothRan both_ran(const PaperTables& t, const std::string& a, const std::string& b) {
  BothRan out;
  double sa = 0, sb = 0;
  for (const auto& q : t.quality) {
    const auto ia = std::find(q.methods.begin(), q.methods.end(), a), ib = std::find(q.methods.begin(), q.methods.end(), b);
    if (ia == q.methods.end() || ib == q.methods.end()) continue;
    const auto& ca = q.cells[ia - q.methods.begin()];
    const auto& cb = q.cells[ib - q.methods.begin()];
    for (size_t s = 0; s < q.scenes.size(); ++s)
      if (ca[s].n > 0 && cb[s].n > 0) sa += ca[s].psnr, sb += cb[s].psnr, ++out.variants;
  }
  if (out.variants > 0) out.a = sa / out.variants, out.b = sb / out.variants;
  return out;
}

// A difference reading: the paper's sign, ours with its interval.
Row difference_row(const PaperTables& t, const std::string& method, const std::string& baseline,
                   const std::string& weather, double paper) {
  Row row{method + " − " + baseline + ", " + weather + " (PSNR)", fmt(paper, 2, true) + " dB", "", "not run"};
  const PairedDifference* d = our_difference(t, method, baseline, weather);
  if (!d) return row;
  const MeanInterval& x = d->psnr;
  row.ours = fmt(x.mean, 2, true) + (std::isfinite(x.half_width) ? " ± " + fmt(x.half_width, 2) : "") + " dB (" +
             std::to_string(x.n) + (x.n == 1 ? " pair)" : " pairs)");
  if (std::isfinite(x.half_width) && std::abs(x.mean) <= x.half_width)
    row.verdict = "unresolved (the interval contains 0)";
  else
    row.verdict = (x.mean > 0) == (paper > 0) ? "reproduced" : "not reproduced";
  return row;
}

std::string best_of(const std::map<std::string, double>& v, bool higher) {
  std::string best;
  for (const auto& [m, x] : v)
    if (std::isfinite(x) && (best.empty() || (higher ? x > v.at(best) : x < v.at(best)))) best = m;
  return best;
}

// "a (1.00) > b (0.50) > ..." in the order of the metric (best first).
std::string ranking(const std::map<std::string, double>& v, bool higher, int decimals) {
  std::vector<std::pair<double, std::string>> order;
  for (const auto& [m, x] : v) order.push_back({x, m});
  std::sort(order.begin(), order.end(), [&](const auto& a, const auto& b) { return higher ? a.first > b.first : a.first < b.first; });
  std::string s;
  for (const auto& [x, m] : order) s += (s.empty() ? "" : " > ") + m + " (" + fmt(x, decimals) + ")";
  return s;
}

}  // namespace

std::string render_agreement(const PaperTables& ours, const PublishedTables& paper) {
  std::ostringstream o;
  o << "## Agreement with the paper\n\n"
    << "Our tables above beside the paper's (" << paper.source << "). Absolute values differ by design (our "
    << "scenes are look-alikes, our LPIPS network may not be the paper's); the rankings, the signs of the "
    << "differences and the cost ratios are what a faithful benchmark should reproduce.\n\n";

  // Rankings of the shared methods, per weather and over both.
  o << "### Ranking of the " << paper.shared_methods.size() << " shared methods\n\n"
    << "| Metric | Weather | Paper | Ours | Kendall's τ |\n|---|---|---|---|---:|\n";
  for (int metric : {0, 2}) {
    for (const std::string w : {"snow", "rain", "both"}) {
      std::map<std::string, double> theirs, mine;
      for (const std::string& m : paper.shared_methods) {
        double a = 0, b = 0;
        for (const std::string x : {"snow", "rain"}) {
          if (w != "both" && x != w) continue;
          const PublishedMetrics& p = paper.averages.at(x).at(m);
          a += (metric == 0 ? p.psnr : p.lpips) / (w == "both" ? 2 : 1);
          b += our_average(ours, x, m, metric) / (w == "both" ? 2 : 1);
        }
        theirs[m] = a;
        if (std::isfinite(b)) mine[m] = b;  // else not run here
      }
      std::vector<double> va, vb;
      for (const auto& [m, x] : mine) va.push_back(theirs[m]), vb.push_back(x);
      const double tau = mine.size() >= 2 ? kendall_tau_b(va, vb) : kNaN;
      o << "| " << (metric == 0 ? "PSNR ↑" : "LPIPS ↓") << " | " << (w == "both" ? "mean of snow and rain" : w)
        << " | " << ranking(theirs, metric == 0, metric == 0 ? 2 : 3) << " | "
        << (mine.empty() ? "not run" : ranking(mine, metric == 0, metric == 0 ? 2 : 3)) << " | " << fmt(tau, 2) << " |\n";
    }
  }
  o << "\nKendall's τ-b between the paper's and our averages of the methods that ran here (1: the same order).\n\n";

  // The readings.
  std::vector<Row> rows;
  for (const std::string w : {"snow", "rain"}) {
    for (int metric : {0, 2}) {
      std::map<std::string, double> theirs, mine;
      for (const std::string& m : paper.shared_methods) {
        const PublishedMetrics& p = paper.averages.at(w).at(m);
        theirs[m] = metric == 0 ? p.psnr : p.lpips;
        mine[m] = our_average(ours, w, m, metric);
      }
      const std::string t = best_of(theirs, metric == 0), b = best_of(mine, metric == 0);
      rows.push_back({"best average " + std::string(metric == 0 ? "PSNR" : "LPIPS") + ", " + w, t,
                      b.empty() ? "" : b + " (" + fmt(mine[b], metric == 0 ? 2 : 3) + ")",
                      b.empty() ? "not run" : b == t ? "reproduced" : "not reproduced"});
    }
  }
  for (const auto& [method, baseline] : {std::pair<const char*, const char*>{"weathergs", "3dgs"}, {"gs-w-lite", "3dgs"},
                                         {"derainnerf", "nerf"}})
    for (const std::string w : {"snow", "rain"})
      rows.push_back(difference_row(ours, method, baseline, w,
                                    paper.averages.at(w).at(method).psnr - paper.averages.at(w).at(baseline).psnr));
  const auto abl = [&](const char* m) { return paper.ablation.count(m) ? paper.ablation.at(m).psnr : kNaN; };
  rows.push_back(difference_row(ours, "weathergs-no-aef", "weathergs", "all", abl("weathergs-no-aef") - abl("weathergs")));
  rows.push_back(difference_row(ours, "weathergs-no-led", "weathergs", "all", abl("weathergs-no-led") - abl("weathergs")));
  {
    Row row{"without the LED worse than without the AEF (PSNR, all variants)",
            fmt(abl("weathergs-no-led"), 2) + " < " + fmt(abl("weathergs-no-aef"), 2), "", "not run"};
    double led = kNaN, aef = kNaN;
    for (size_t m = 0; m < ours.ablation.methods.size(); ++m) {
      if (ours.ablation.average[m].n == 0) continue;
      if (ours.ablation.methods[m] == "weathergs-no-led") led = ours.ablation.average[m].psnr;
      if (ours.ablation.methods[m] == "weathergs-no-aef") aef = ours.ablation.average[m].psnr;
    }
    std::string over;
    if (!std::isfinite(led) || !std::isfinite(aef)) {
      // Table III averages methods with every variant; a matrix that runs an ablation on some variants
      // only (weathergs-no-led on rain) is still read, over the variants both ran, and says so.
      const BothRan both = both_ran(ours, "weathergs-no-led", "weathergs-no-aef");
      if (both.variants > 0) {
        led = both.a, aef = both.b;
        over = " (the " + std::to_string(both.variants) + (both.variants == 1 ? " variant" : " variants") + " both ran)";
      }
    }
    if (std::isfinite(led) && std::isfinite(aef)) {
      row.ours = fmt(led, 2) + (led < aef ? " < " : " ≥ ") + fmt(aef, 2) + over;
      row.verdict = (led < aef) == (abl("weathergs-no-led") < abl("weathergs-no-aef")) ? "reproduced" : "not reproduced";
    }
    rows.push_back(row);
  }
  // Cost: the radiance-field backend against 3DGS (weathergs-nerf against weathergs), Table IV.
  const CostRow* nerf = nullptr;
  const CostRow* gs = nullptr;
  for (const auto& c : ours.cost) {
    if (c.method == "weathergs-nerf") nerf = &c;
    if (c.method == "weathergs") gs = &c;
  }
  // Wall seconds grow when other jobs share the cores, CPU seconds do not: the training ratio reads
  // the CPU seconds when both methods record them, so that it does not depend on what ran beside.
  const bool cpu = nerf && gs && std::isfinite(nerf->train_cpu_seconds) && std::isfinite(gs->train_cpu_seconds);
  struct Ratio { const char* what; double paper; double CostRow::*field; };
  for (const Ratio& q : {Ratio{cpu ? "training time (ours: CPU seconds)" : "training time",
                               paper.nerf_train_min / paper.gs_train_min,
                               cpu ? &CostRow::train_cpu_seconds : &CostRow::train_seconds},
                         Ratio{"render time per view", paper.nerf_render_s / paper.gs_render_s, &CostRow::render_ms_per_view},
                         Ratio{"memory (paper: GPU; ours: peak resident set)", paper.nerf_memory_gb / paper.gs_memory_gb,
                               &CostRow::peak_rss_mb}}) {
    Row row{std::string("weathergs-nerf / weathergs, ") + q.what, fmt(q.paper, 1) + "x", "", "not run"};
    if (nerf && gs && std::isfinite(nerf->*q.field) && std::isfinite(gs->*q.field) && gs->*q.field > 0) {
      const double r = nerf->*q.field / (gs->*q.field);
      row.ours = fmt(r, 1) + "x";
      row.verdict = (r > 1) == (q.paper > 1) ? "reproduced" : "not reproduced";
    }
    rows.push_back(row);
  }
  o << "### The paper's readings\n\n| Reading | Paper | Ours | Verdict |\n|---|---|---|---|\n";
  for (const Row& r : rows) o << "| " << r.reading << " | " << r.paper << " | " << (r.ours.empty() ? "–" : r.ours) << " | " << r.verdict << " |\n";
  o << "\nReproduced: the same winner, the same sign of a difference (\"unresolved\" when our 95% interval over "
       "paired runs contains 0), the same order, a cost ratio on the same side of 1. Differences are ours "
       "paired by variant and seed (the table above); the paper's are differences of its averages.\n\n";
  return o.str();
}

}  // namespace weathergs::evaluator
