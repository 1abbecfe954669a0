#include "evaluator/paper_tables.h"

#include <algorithm>
#include <filesystem>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <set>
#include <sstream>

namespace weathergs::evaluator {

namespace {

namespace fs = std::filesystem;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Table III's rows in the paper's order: w/o AEF, w/o LED, full.
const char* kAblationMethods[3] = {"weathergs-no-aef", "weathergs-no-led", "weathergs"};

std::string variant_of(const Results& r) {
  const std::string scene = r.scene.empty() ? r.dataset : r.scene;
  return r.weather.empty() ? scene : scene + "_" + r.weather;
}

// Competitors first (order of appearance), reference lines last; cells and averages follow.
void move_references_last(LeaderboardTable& t) {
  std::vector<size_t> order(t.methods.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_partition(order.begin(), order.end(), [&](size_t m) { return !is_reference_method(t.methods[m]); });
  LeaderboardTable o = t;
  o.reference.assign(order.size(), false);
  for (size_t k = 0; k < order.size(); ++k) {
    o.methods[k] = t.methods[order[k]];
    o.cells[k] = t.cells[order[k]];
    o.average[k] = t.average[order[k]];
    o.reference[k] = is_reference_method(o.methods[k]);
  }
  t = std::move(o);
}

int weather_rank(const std::string& w) { return w == "snow" ? 0 : w == "rain" ? 1 : 2; }

const char* kRoman[] = {"I", "II", "III", "IV", "V", "VI", "VII", "VIII"};

// A number of method_info, or NaN when absent or not a number.
double info_number(const Json& info, const char* key) {
  if (!info.is_object() || !info.contains(key) || !info[key].is_number()) return kNaN;
  return info[key].get<double>();
}

// The seed a result was trained with: method_info.seed, else the workflow's folder name seed<N>
// (runs/<variant>/<method>/seed<N>/results.json); a result with neither is a seed of its own.
std::string seed_key(const LoadedResults& lr) {
  const Json& info = lr.results.method_info;
  if (info.is_object() && info.contains("seed") && info["seed"].is_number_integer())
    return std::to_string(info["seed"].get<int64_t>());
  const std::string folder = fs::path(lr.path).parent_path().filename().string();
  if (folder.size() > 4 && folder.compare(0, 4, "seed") == 0 &&
      folder.find_first_not_of("0123456789", 4) == std::string::npos)
    return std::to_string(std::stoll(folder.substr(4)));
  return "file:" + lr.path;
}

std::string scene_of(const Results& r) { return r.scene.empty() ? r.dataset : r.scene; }

double mean_of(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s / double(v.size());
}

// PSNR, SSIM and LPIPS (NaN when absent) of a result.
std::array<double, 3> metrics_of(const Results& r) {
  return {r.metrics.psnr, r.metrics.ssim, r.metrics.lpips ? *r.metrics.lpips : kNaN};
}

// The 95% intervals, over the seeds that ran on all `groups` groups (scenes or variants), of each
// seed's mean over the groups (a group's repeated results of one seed averaged first).
std::array<MeanInterval, 3> over_seeds(const std::vector<const LoadedResults*>& rs,
                                       std::string (*group_of)(const Results&), size_t groups) {
  std::map<std::string, std::map<std::string, std::array<std::vector<double>, 3>>> by_seed;
  for (const LoadedResults* lr : rs) {
    auto& v = by_seed[seed_key(*lr)][group_of(lr->results)];
    const auto m = metrics_of(lr->results);
    for (int k = 0; k < 3; ++k) v[k].push_back(m[k]);
  }
  std::array<std::vector<double>, 3> per_seed;
  for (const auto& [seed, by_group] : by_seed) {
    if (by_group.size() != groups) continue;
    std::array<double, 3> sum{};
    for (const auto& [group, v] : by_group)
      for (int k = 0; k < 3; ++k) sum[k] += mean_of(v[k]);
    for (int k = 0; k < 3; ++k) per_seed[k].push_back(sum[k] / double(groups));
  }
  std::array<MeanInterval, 3> out;
  for (int k = 0; k < 3; ++k) out[k] = mean_ci95(per_seed[k]);
  return out;
}

// An average cell gets the interval over seeds when at least two seeds ran on every group.
void set_seed_interval(CellStats& avg, const std::array<MeanInterval, 3>& ci) {
  if (avg.n == 0 || ci[0].n < 2) return;
  avg.n = ci[0].n;
  avg.psnr_ci = ci[0].half_width;
  avg.ssim_ci = ci[1].half_width;
  if (avg.has_lpips) avg.lpips_ci = ci[2].half_width;
}

// WeatherGS against vanilla 3DGS, each ablation against the full method, and the two differences the
// paper reads between its baselines (GS-W against 3DGS, DerainNeRF against NeRF).
const std::pair<const char*, const char*> kComparisons[] = {
    {"weathergs", "3dgs"},           {"weathergs-no-aef", "weathergs"}, {"weathergs-no-led", "weathergs"},
    {"gs-w-lite", "3dgs"},           {"derainnerf", "nerf"}};

std::vector<PairedDifference> paired_differences(const std::vector<LoadedResults>& results,
                                                 const std::vector<std::string>& weathers, const MixedData& mixed,
                                                 const MixedRecipes& recipes) {
  std::vector<PairedDifference> out;
  for (const auto& [method, baseline] : kComparisons) {
    std::vector<std::string> groups = weathers;
    groups.push_back("all");
    for (const std::string& w : groups) {
      // (variant, seed) -> that method's metrics (repeats averaged), for the method and the baseline.
      std::map<std::pair<std::string, std::string>, std::array<std::vector<double>, 3>> a, b;
      std::set<std::pair<std::string, std::string>> odd;  // (variant, seed) pairs with a result on other data
      std::set<std::pair<std::string, std::string>> odd_recipe;  // ... of another recipe
      for (const auto& lr : results) {
        if (w != "all" && lr.results.weather != w) continue;
        auto* side = lr.results.method == method ? &a : lr.results.method == baseline ? &b : nullptr;
        if (!side) continue;
        if (mixed.is_odd(lr)) odd.insert({variant_of(lr.results), seed_key(lr)});
        if (recipes.is_odd(lr)) odd_recipe.insert({variant_of(lr.results), seed_key(lr)});
        auto& v = (*side)[{variant_of(lr.results), seed_key(lr)}];
        const auto m = metrics_of(lr.results);
        for (int k = 0; k < 3; ++k) v[k].push_back(m[k]);
      }
      std::array<std::vector<double>, 3> d;
      bool other_data = false, other_recipe = false;
      for (const auto& [key, va] : a) {
        const auto it = b.find(key);
        if (it == b.end()) continue;
        other_data = other_data || odd.count(key) > 0;
        other_recipe = other_recipe || odd_recipe.count(key) > 0;
        for (int k = 0; k < 3; ++k) {
          const double x = mean_of(va[k]) - mean_of(it->second[k]);
          if (std::isfinite(x)) d[k].push_back(x);
        }
      }
      if (d[0].empty()) continue;
      out.push_back({method, baseline, w, mean_ci95(d[0]), mean_ci95(d[1]), mean_ci95(d[2]), other_data, other_recipe});
    }
  }
  return out;
}

}  // namespace

PaperTables build_paper_tables(const std::vector<LoadedResults>& results, const LeaderboardOptions& options) {
  PaperTables out;
  out.quality = build_leaderboard(results, options);  // refuses mixed data unless allowed
  const MixedData mixed = find_mixed_data(results, options);
  for (const MixedData::Variant& v : mixed.mixed)
    out.data_notes.push_back(v.scene + (v.weather.empty() ? "" : " " + v.weather) + ": " + v.identities);
  const MixedRecipes recipes = find_mixed_recipes(results, options);
  out.recipe_notes = recipes.notes("");
  std::stable_sort(out.quality.begin(), out.quality.end(), [](const LeaderboardTable& a, const LeaderboardTable& b) {
    return weather_rank(a.weather) < weather_rank(b.weather);
  });
  for (size_t i = 0; i < out.quality.size(); ++i) {
    LeaderboardTable& t = out.quality[i];
    std::string w = t.weather.empty() ? "unspecified weather" : t.weather;
    w[0] = char(std::toupper(static_cast<unsigned char>(w[0])));
    t.title = std::string("Table ") + kRoman[std::min<size_t>(i, 7)] + ": " + w;
    t.ci95 = true;
    move_references_last(t);
    for (size_t m = 0; m < t.methods.size(); ++m) {
      std::vector<const LoadedResults*> rs;
      for (const auto& lr : results)
        if (lr.results.weather == t.weather && lr.results.method == t.methods[m]) rs.push_back(&lr);
      set_seed_interval(t.average[m], over_seeds(rs, scene_of, t.scenes.size()));
    }
  }
  const std::string table3 = std::string("Table ") + kRoman[std::min<size_t>(out.quality.size(), 7)];

  // Table III: every variant any result names; a method's mean over variants of its per-variant
  // means (seeds averaged first), only when it ran on every variant.
  std::vector<std::string> variants;
  for (const auto& lr : results) {
    const std::string v = variant_of(lr.results);
    if (std::find(variants.begin(), variants.end(), v) == variants.end()) variants.push_back(v);
  }
  out.ablation_variants = variants;
  LeaderboardTable& a = out.ablation;
  a.title = table3 + ": ablation, mean over all " + std::to_string(variants.size()) + " variants";
  a.weather = "all";
  a.average_label = "All variants";
  a.average_note = "All variants: the mean over " + std::to_string(variants.size()) +
                   " variants of each variant's mean over seeds, only for methods with every variant.";
  a.protocol = out.quality.empty() ? Protocol{} : out.quality.front().protocol;
  a.ci95 = true;
  a.data_notes = out.data_notes;
  a.recipe_notes = out.recipe_notes;
  for (const char* m : kAblationMethods) {
    std::map<std::string, std::vector<const Results*>> per_variant;
    for (const auto& lr : results) {
      if (lr.results.method != m) continue;
      // build_leaderboard checked each weather; this table spans weathers.
      if (!(lr.results.protocol == a.protocol))
        throw InputError(lr.path, "protocol differs from the other weathers' (" + lr.results.protocol.to_string() +
                                      " vs " + a.protocol.to_string() + "): the ablation averages over all variants");
      per_variant[variant_of(lr.results)].push_back(&lr.results);
    }
    if (per_variant.empty()) continue;
    CellStats avg;
    for (const auto& lr : results) {
      avg.other_data = avg.other_data || (lr.results.method == m && mixed.is_odd(lr));
      avg.other_recipe = avg.other_recipe || (lr.results.method == m && recipes.is_odd(lr));
    }
    bool complete = per_variant.size() == variants.size(), lp = true;
    if (complete) {
      for (const auto& [v, rs] : per_variant) {
        double p = 0, s = 0, l = 0;
        for (const Results* r : rs) {
          p += r->metrics.psnr;
          s += r->metrics.ssim;
          if (r->metrics.lpips) l += *r->metrics.lpips; else lp = false;
        }
        const double n = double(rs.size());
        avg.psnr += p / n; avg.ssim += s / n; avg.lpips += l / n;
      }
      const double k = double(variants.size());
      avg.n = 1;
      avg.psnr /= k; avg.ssim /= k; avg.lpips /= k;
      avg.has_lpips = lp;
    }
    std::vector<const LoadedResults*> rs;
    for (const auto& lr : results)
      if (lr.results.method == m) rs.push_back(&lr);
    set_seed_interval(avg, over_seeds(rs, variant_of, variants.size()));
    a.methods.push_back(m);
    a.cells.emplace_back();
    a.average.push_back(avg);
  }
  a.reference.assign(a.methods.size(), false);

  // Table IV: cost per method, in the order of the quality tables' rows.
  std::vector<std::string> methods;
  for (const auto& t : out.quality)
    for (const auto& m : t.methods)
      if (std::find(methods.begin(), methods.end(), m) == methods.end()) methods.push_back(m);
  std::stable_partition(methods.begin(), methods.end(), [](const std::string& m) { return !is_reference_method(m); });
  for (const std::string& m : methods) {
    CostRow row;
    row.method = m;
    row.reference = is_reference_method(m);
    std::vector<double> train, train_cpu, restore, render, rss, gaussians;
    for (const auto& lr : results) {
      if (lr.results.method != m) continue;
      ++row.runs;
      const Json& info = lr.results.method_info;
      auto push = [](std::vector<double>& v, double x) { if (std::isfinite(x)) v.push_back(x); };
      push(train, info_number(info, "train_seconds"));
      push(train_cpu, info_number(info, "train_cpu_seconds"));
      const double f = info_number(info, "filter_seconds"), d = info_number(info, "detect_seconds");
      push(restore, (std::isfinite(f) ? f : 0) + (std::isfinite(d) ? d : 0));
      const double views = double(lr.results.per_view.size());
      const double rs = info_number(info, "render_seconds");
      if (views > 0) push(render, 1000 * rs / views);
      push(rss, info_number(info, "peak_rss_mb"));
      push(gaussians, info_number(info, "num_gaussians"));
    }
    double unused_sd;
    mean_std(train, row.train_seconds, row.train_seconds_std);
    mean_std(train_cpu, row.train_cpu_seconds, unused_sd);
    if (int(train_cpu.size()) != row.runs) row.train_cpu_seconds = std::numeric_limits<double>::quiet_NaN();
    mean_std(restore, row.restoration_seconds, unused_sd);
    mean_std(render, row.render_ms_per_view, unused_sd);
    mean_std(rss, row.peak_rss_mb, unused_sd);
    mean_std(gaussians, row.gaussians, unused_sd);
    out.cost.push_back(row);
  }
  std::vector<std::string> weathers;
  for (const auto& t : out.quality) weathers.push_back(t.weather);
  out.differences = paired_differences(results, weathers, mixed, recipes);
  return out;
}

namespace {

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "";
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(decimals);
  o << v;
  return o.str();
}

struct CostColumn {
  const char* title;
  int decimals;
  double CostRow::*field;
};
const CostColumn kCostColumns[] = {{"Training (s)", 0, &CostRow::train_seconds},
                                   {"Training CPU (s)", 0, &CostRow::train_cpu_seconds},
                                   {"AEF + LED (s)", 1, &CostRow::restoration_seconds},
                                   {"Render (ms/view)", 1, &CostRow::render_ms_per_view},
                                   {"Peak memory (MB)", 0, &CostRow::peak_rss_mb},
                                   {"Gaussians", 0, &CostRow::gaussians}};

std::string cost_cell(const CostRow& r, const CostColumn& c, const char* pm) {
  std::string s = fixed(r.*(c.field), c.decimals);
  if (!s.empty() && c.field == &CostRow::train_seconds && r.runs > 1) s += pm + fixed(r.train_seconds_std, 0);
  return s;
}

std::string cost_label(const CostRow& r) { return r.reference ? r.method + " (reference)" : r.method; }

const char* kCostNote =
    "Mean over each method's runs (all variants and seeds; training time with its standard deviation). "
    "Training: the optimisation only (3DGS, or the radiance field for the NeRF-family methods), wall seconds, "
    "which grow when other jobs share the cores; Training CPU: its CPU seconds over every thread, which grow "
    "less but not to nothing, so compare runs made under the same load (empty unless every run records "
    "them); AEF + LED: "
    "the particle filter and the lens detector before it; render: per test view; "
    "peak memory: the training process's peak resident set.";

std::string render_cost(const std::vector<CostRow>& rows, const std::string& title, TableFormat format) {
  std::ostringstream o;
  switch (format) {
    case TableFormat::kMarkdown:
      o << "## " << title << "\n\n| Method | Runs |";
      for (const auto& c : kCostColumns) o << " " << c.title << " |";
      o << "\n|---|---:|";
      for (size_t i = 0; i < std::size(kCostColumns); ++i) o << "---:|";
      o << "\n";
      for (const auto& r : rows) {
        o << "| " << cost_label(r) << " | " << r.runs << " |";
        for (const auto& c : kCostColumns) {
          const std::string s = cost_cell(r, c, " ± ");
          o << " " << (s.empty() ? "–" : s) << " |";
        }
        o << "\n";
      }
      o << "\n" << kCostNote << "\n\n";
      break;
    case TableFormat::kCsv:
      o << "method,runs,train_seconds,train_seconds_std,restoration_seconds,render_ms_per_view,peak_rss_mb,gaussians\n";
      for (const auto& r : rows)
        o << csv_escape(r.method) << "," << r.runs << "," << fixed(r.train_seconds, 3) << ","
          << fixed(r.train_seconds_std, 3) << "," << fixed(r.restoration_seconds, 3) << ","
          << fixed(r.render_ms_per_view, 3) << "," << fixed(r.peak_rss_mb, 1) << "," << fixed(r.gaussians, 0) << "\n";
      break;
    case TableFormat::kLatex:
      o << "% " << title << ". " << kCostNote << "\n";
      o << "\\begin{table}[t]\n\\centering\n\\caption{" << latex_escape(title) << "}\n\\begin{tabular}{lr"
        << std::string(std::size(kCostColumns), 'r') << "}\n\\toprule\nMethod & Runs";
      for (const auto& c : kCostColumns) o << " & " << latex_escape(c.title);
      o << " \\\\\n\\midrule\n";
      for (const auto& r : rows) {
        o << latex_escape(cost_label(r)) << " & " << r.runs;
        for (const auto& c : kCostColumns) {
          const std::string s = cost_cell(r, c, "$\\pm$");
          o << " & " << (s.empty() ? "--" : s);
        }
        o << " \\\\\n";
      }
      o << "\\bottomrule\n\\end{tabular}\n\\end{table}\n\n";
      break;
    case TableFormat::kHtml:
      o << "<h2>" << html_escape(title) << "</h2>\n<table>\n<thead>\n<tr><th>Method</th><th>Runs</th>";
      for (const auto& c : kCostColumns) o << "<th>" << html_escape(c.title) << "</th>";
      o << "</tr>\n</thead>\n<tbody>\n";
      for (const auto& r : rows) {
        o << "<tr><td class=\"method\">" << html_escape(cost_label(r)) << "</td><td>" << r.runs << "</td>";
        for (const auto& c : kCostColumns) {
          const std::string s = cost_cell(r, c, " &plusmn; ");
          o << "<td>" << (s.empty() ? "&ndash;" : s) << "</td>";
        }
        o << "</tr>\n";
      }
      o << "</tbody>\n</table>\n<p class=\"note\">" << html_escape(kCostNote) << "</p>\n";
      break;
  }
  return o.str();
}

std::string signed_interval(const MeanInterval& d, int decimals, const char* pm) {
  if (d.n == 0 || !std::isfinite(d.mean)) return "";
  std::string s = (d.mean >= 0 ? "+" : "") + fixed(d.mean, decimals);
  if (std::isfinite(d.half_width)) s += pm + fixed(d.half_width, decimals);
  return s;
}

const char* kDifferenceNote =
    "Paired differences: method minus baseline over the (variant, seed) pairs both ran, mean ± the "
    "half-width of its 95% Student-t interval (none with one pair). PSNR and SSIM: positive = the method "
    "is better; LPIPS: negative = the method is better.";

std::string render_differences(const std::vector<PairedDifference>& rows, const std::string& title, TableFormat format,
                               const std::vector<std::string>& data_notes, const std::vector<std::string>& recipe_notes) {
  const char* header[] = {"Difference", "Weather", "Pairs", "ΔPSNR (dB)", "ΔSSIM", "ΔLPIPS"};
  bool marked = false;
  bool marked_recipe = false;
  for (const auto& r : rows) {
    marked = marked || r.other_data;
    marked_recipe = marked_recipe || r.other_recipe;
  }
  const std::string note = std::string(kDifferenceNote) + (marked ? " " + other_data_note(data_notes) : "") +
                           (marked_recipe ? " " + other_recipe_note(recipe_notes) : "");
  std::ostringstream o;
  auto cells = [&](const PairedDifference& r, const char* pm) {
    const std::string marks = std::string(r.other_data ? kOtherDataMarker : "") + (r.other_recipe ? kOtherRecipeMarker : "");
    const std::string mark = marks.empty() ? "" : " " + marks;
    return std::vector<std::string>{r.method + " − " + r.baseline + mark, r.weather, std::to_string(r.psnr.n),
                                    signed_interval(r.psnr, 2, pm), signed_interval(r.ssim, 3, pm),
                                    signed_interval(r.lpips, 3, pm)};
  };
  switch (format) {
    case TableFormat::kMarkdown:
      o << "## " << title << "\n\n|";
      for (const char* h : header) o << " " << h << " |";
      o << "\n|---|---|---:|---:|---:|---:|\n";
      for (const auto& r : rows) {
        o << "|";
        for (const std::string& c : cells(r, " ± ")) o << " " << (c.empty() ? "–" : c) << " |";
        o << "\n";
      }
      o << "\n" << note << "\n\n";
      break;
    case TableFormat::kCsv:
      o << "method,baseline,weather,pairs,psnr_diff,psnr_ci95,ssim_diff,ssim_ci95,lpips_diff,lpips_ci95\n";
      for (const auto& r : rows) {
        o << csv_escape(r.method) << "," << csv_escape(r.baseline) << "," << csv_escape(r.weather) << "," << r.psnr.n;
        for (const MeanInterval* m : {&r.psnr, &r.ssim, &r.lpips}) o << "," << fixed(m->mean, 6) << "," << fixed(m->half_width, 6);
        o << "\n";
      }
      break;
    case TableFormat::kLatex:
      o << "% " << title << ". " << note << "\n";
      o << "\\begin{table}[t]\n\\centering\n\\caption{" << latex_escape(title)
        << "}\n\\begin{tabular}{llrrrr}\n\\toprule\nDifference & Weather & Pairs & $\\Delta$PSNR (dB) & "
           "$\\Delta$SSIM & $\\Delta$LPIPS \\\\\n\\midrule\n";
      for (const auto& r : rows) {
        std::vector<std::string> c = cells(r, "$\\pm$");
        c[0] = latex_escape(r.method + " -- " + r.baseline) + (r.other_data ? "$^\\dagger$" : "") +
               (r.other_recipe ? "$^\\ddagger$" : "");
        for (size_t i = 0; i < c.size(); ++i)
          o << (i ? " & " : "") << (c[i].empty() ? "--" : (i == 1 ? latex_escape(c[i]) : c[i]));
        o << " \\\\\n";
      }
      o << "\\bottomrule\n\\end{tabular}\n\\end{table}\n\n";
      break;
    case TableFormat::kHtml:
      o << "<h2>" << html_escape(title) << "</h2>\n<table>\n<thead>\n<tr>";
      for (const char* h : header) o << "<th>" << html_escape(h) << "</th>";
      o << "</tr>\n</thead>\n<tbody>\n";
      for (const auto& r : rows) {
        o << "<tr>";
        for (const std::string& c : cells(r, " ± ")) o << "<td>" << (c.empty() ? "&ndash;" : html_escape(c)) << "</td>";
        o << "</tr>\n";
      }
      o << "</tbody>\n</table>\n<p class=\"note\">" << html_escape(note) << "</p>\n";
      break;
  }
  return o.str();
}

}  // namespace

std::string render_paper_tables(const PaperTables& t, TableFormat format, const std::string& note) {
  std::string o = document_begin(format, "WeatherGS benchmark: the paper's tables", note);
  auto separate = [&] { if (format == TableFormat::kCsv && !o.empty()) o += "\n"; };
  for (const auto& q : t.quality) {
    separate();
    o += render_table(q, format, true);
  }
  const std::string table4 = std::string("Table ") + kRoman[std::min<size_t>(t.quality.size() + 1, 7)] +
                             ": computational cost";
  if (!t.ablation.methods.empty()) {
    separate();
    o += render_table(t.ablation, format, true);
  } else if (format == TableFormat::kMarkdown) {
    o += "(No ablation table: no results of weathergs-no-aef, weathergs-no-led or weathergs.)\n\n";
  }
  separate();
  o += render_cost(t.cost, table4, format);
  if (!t.differences.empty()) {
    separate();
    o += render_differences(t.differences, "Paired differences", format, t.data_notes, t.recipe_notes);
  }
  return o + document_end(format);
}

}  // namespace weathergs::evaluator
