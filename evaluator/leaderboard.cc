#include "evaluator/leaderboard.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

#include "evaluator/statistics.h"

namespace weathergs::evaluator {

TableFormat parse_table_format(const std::string& name) {
  if (name == "md" || name == "markdown") return TableFormat::kMarkdown;
  if (name == "csv") return TableFormat::kCsv;
  if (name == "latex" || name == "tex") return TableFormat::kLatex;
  if (name == "html") return TableFormat::kHtml;
  throw InputError("table format", "unknown table format '" + name + "' (expected md, csv, latex or html)");
}

namespace {

template <typename T>
size_t index_of(std::vector<T>& v, const T& x) {
  auto it = std::find(v.begin(), v.end(), x);
  if (it != v.end()) return size_t(it - v.begin());
  v.push_back(x);
  return v.size() - 1;
}

CellStats stats(const std::vector<const Results*>& rs) {
  CellStats c;
  c.n = int(rs.size());
  if (rs.empty()) return c;
  std::vector<double> p, s, l;
  c.has_lpips = true;
  for (const Results* r : rs) {
    p.push_back(r->metrics.psnr);
    s.push_back(r->metrics.ssim);
    if (r->metrics.lpips) l.push_back(*r->metrics.lpips); else c.has_lpips = false;
  }
  mean_std(p, c.psnr, c.psnr_std);
  mean_std(s, c.ssim, c.ssim_std);
  c.psnr_ci = mean_ci95(p).half_width;
  c.ssim_ci = mean_ci95(s).half_width;
  if (c.has_lpips) {
    mean_std(l, c.lpips, c.lpips_std);
    c.lpips_ci = mean_ci95(l).half_width;
  }
  return c;
}

}  // namespace

void mean_std(const std::vector<double>& x, double& mean, double& sd) {
  mean = 0;
  for (double v : x) mean += v;
  mean /= double(x.size());
  sd = 0;
  if (std::isinf(mean)) return;
  for (double v : x) sd += (v - mean) * (v - mean);
  sd = std::sqrt(sd / double(x.size()));
}

std::string csv_escape(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (char c : s) o += c == '"' ? std::string("\"\"") : std::string(1, c);
  return o + "\"";
}

std::string latex_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (std::string("&%$#_{}").find(c) != std::string::npos) o += '\\';
    o += c;
  }
  return o;
}

std::string html_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

// Upper bounds and ground-truth-assisted runs: shown, never ranked (methods/method.h).
bool is_reference_method(const std::string& method) {
  return method == "oracle" || method == "gt-masks" || method == "nerf-oracle";
}

namespace {

std::string scene_key(const Results& r) { return r.scene.empty() ? r.dataset : r.scene; }
std::string identity_key(const Results& r) { return r.dataset_identity ? r.dataset_identity->sha256 : ""; }

std::string variant_label(const std::pair<std::string, std::string>& weather_scene) {
  return weather_scene.first.empty() ? weather_scene.second : weather_scene.second + " " + weather_scene.first;
}

// "2 on 1a2b3c4d5e6f (the column's); 1 on 9f8e7d6c5b4a (noise)": how many results of a variant on
// each identity, and which methods the odd ones are.
std::string identities_line(const std::vector<const LoadedResults*>& group, const std::vector<std::string>& ids,
                            const std::string& ref) {
  std::string line;
  for (const std::string& id : ids) {
    int n = 0;
    std::vector<std::string> methods;
    for (const LoadedResults* lr : group) {
      if (identity_key(lr->results) != id) continue;
      ++n;
      if (std::find(methods.begin(), methods.end(), lr->results.method) == methods.end())
        methods.push_back(lr->results.method);
    }
    std::string who;
    for (const std::string& m : methods) who += (who.empty() ? "" : ", ") + m;
    line += (line.empty() ? "" : "; ") + std::to_string(n) + (id.empty() ? " with none recorded" : " on " + id.substr(0, 12)) +
            (id == ref ? " (the column's)" : " (" + who + ")");
  }
  return line;
}

}  // namespace

MixedData find_mixed_data(const std::vector<LoadedResults>& results, const LeaderboardOptions& options) {
  std::vector<std::pair<std::string, std::string>> order;  // variants as (weather, scene), first appearance
  std::map<std::pair<std::string, std::string>, std::vector<const LoadedResults*>> by_variant;
  for (const auto& lr : results) {
    const auto key = std::make_pair(lr.results.weather, scene_key(lr.results));
    if (!by_variant.count(key)) order.push_back(key);
    by_variant[key].push_back(&lr);
  }
  MixedData out;
  for (const auto& key : order) {
    const auto& group = by_variant[key];
    std::vector<std::string> ids;  // "" = none recorded; first appearance
    std::map<std::string, int> count;
    for (const LoadedResults* lr : group)
      if (count[identity_key(lr->results)]++ == 0) ids.push_back(identity_key(lr->results));
    if (ids.size() < 2) continue;  // one dataset, or none recorded by any
    std::string ref;
    for (const std::string& id : ids)
      if (!id.empty() && (ref.empty() || count[id] > count[ref])) ref = id;
    const LoadedResults* on_ref = nullptr;
    for (const LoadedResults* lr : group)
      if (!on_ref && identity_key(lr->results) == ref) on_ref = lr;
    for (const LoadedResults* lr : group) {
      if (identity_key(lr->results) == ref) continue;
      if (!options.allow_mixed_data)
        throw InputError(lr->path, "scored on other data than " + on_ref->path + " (both " + variant_label(key) +
                                       "): dataset identity " + dataset_identity_text(lr->results) + " vs " + ref +
                                       "; results on different datasets cannot share a column: score them on one "
                                       "dataset, or pass --allow-mixed-data to mark them");
      out.odd.insert(lr);
    }
    out.mixed.push_back({key.first, key.second, identities_line(group, ids, ref)});
  }
  return out;
}

std::string other_data_note(const std::vector<std::string>& lines) {
  if (lines.empty()) return "";
  std::string o = std::string(kOtherDataMarker) +
                  " Includes results scored on other data than the rest of their variant (scene and weather); the "
                  "mixed variants' dataset identities, by their first 12 hex digits: ";
  for (size_t i = 0; i < lines.size(); ++i) o += (i ? "; " : "") + lines[i];
  return o + ".";
}

std::vector<LeaderboardTable> build_leaderboard(const std::vector<LoadedResults>& results,
                                                const LeaderboardOptions& options) {
  if (results.empty()) throw InputError("leaderboard", "no results files given");
  const MixedData mixed = find_mixed_data(results, options);
  const MixedRecipes recipes = find_mixed_recipes(results, options);
  std::vector<std::string> weathers;
  std::map<std::string, std::vector<const LoadedResults*>> by_weather;
  for (const auto& lr : results) {
    index_of(weathers, lr.results.weather);
    by_weather[lr.results.weather].push_back(&lr);
  }
  std::vector<LeaderboardTable> tables;
  for (const std::string& w : weathers) {
    LeaderboardTable t;
    t.weather = w;
    const auto& group = by_weather[w];
    t.protocol = group.front()->results.protocol;
    std::map<std::pair<size_t, size_t>, std::vector<const Results*>> cell_results;
    std::set<std::pair<size_t, size_t>> odd_cells, odd_recipe_cells;
    for (const MixedData::Variant& v : mixed.mixed)
      if (v.weather == w) t.data_notes.push_back(v.scene + ": " + v.identities);
    t.recipe_notes = recipes.notes(w);
    for (const LoadedResults* lr : group) {
      if (!(lr->results.protocol == t.protocol))
        throw InputError(lr->path, "protocol differs from " + group.front()->path + " (" +
                                       lr->results.protocol.to_string() + " vs " + t.protocol.to_string() +
                                       "): results scored differently cannot share a table");
      size_t m = index_of(t.methods, lr->results.method);
      size_t s = index_of(t.scenes, lr->results.scene.empty() ? lr->results.dataset : lr->results.scene);
      cell_results[{m, s}].push_back(&lr->results);
      if (mixed.is_odd(*lr)) odd_cells.insert({m, s});
      if (recipes.is_odd(*lr)) odd_recipe_cells.insert({m, s});
    }
    t.cells.assign(t.methods.size(), std::vector<CellStats>(t.scenes.size()));
    for (auto& [key, rs] : cell_results) t.cells[key.first][key.second] = stats(rs);
    for (const auto& [m, s] : odd_cells) t.cells[m][s].other_data = true;
    for (const auto& [m, s] : odd_recipe_cells) t.cells[m][s].other_recipe = true;
    t.average.resize(t.methods.size());
    for (size_t m = 0; m < t.methods.size(); ++m) {
      CellStats avg;
      bool complete = true, lp = true;
      for (size_t s = 0; s < t.scenes.size(); ++s) {
        const CellStats& c = t.cells[m][s];
        if (c.n == 0) { complete = false; break; }
        avg.psnr += c.psnr; avg.ssim += c.ssim; avg.lpips += c.lpips;
        lp = lp && c.has_lpips;
        avg.other_data = avg.other_data || c.other_data;
        avg.other_recipe = avg.other_recipe || c.other_recipe;
      }
      if (complete) {
        const double k = double(t.scenes.size());
        avg.n = 1;
        avg.psnr /= k; avg.ssim /= k; avg.lpips /= k;
        avg.has_lpips = lp;
      } else {
        avg = CellStats{};
      }
      t.average[m] = avg;
    }
    t.reference.resize(t.methods.size());
    for (size_t m = 0; m < t.methods.size(); ++m) t.reference[m] = is_reference_method(t.methods[m]);
    tables.push_back(std::move(t));
  }
  return tables;
}

namespace {

struct Column {
  std::string group;   // scene name or "Average"
  int metric;          // 0 psnr, 1 ssim, 2 lpips
};
const char* kMetricName[3] = {"PSNR", "SSIM", "LPIPS"};
const int kDecimals[3] = {2, 3, 3};
const bool kHigherBetter[3] = {true, true, false};

std::vector<Column> columns(const LeaderboardTable& t) {
  std::vector<Column> cols;
  for (const auto& s : t.scenes)
    for (int k = 0; k < 3; ++k) cols.push_back({s, k});
  for (int k = 0; k < 3; ++k) cols.push_back({t.average_label, k});
  return cols;
}

const CellStats& cell(const LeaderboardTable& t, size_t m, size_t col) {
  const size_t s = col / 3;
  return s < t.scenes.size() ? t.cells[m][s] : t.average[m];
}

bool is_reference(const LeaderboardTable& t, size_t m) { return m < t.reference.size() && t.reference[m]; }

std::string method_label(const LeaderboardTable& t, size_t m) {
  return is_reference(t, m) ? t.methods[m] + " (reference)" : t.methods[m];
}

bool present(const CellStats& c, int k) { return c.n > 0 && (k != 2 || c.has_lpips); }
double value(const CellStats& c, int k) { return k == 0 ? c.psnr : k == 1 ? c.ssim : c.lpips; }
double spread(const LeaderboardTable& t, const CellStats& c, int k) {
  if (t.ci95) return k == 0 ? c.psnr_ci : k == 1 ? c.ssim_ci : c.lpips_ci;
  return k == 0 ? c.psnr_std : k == 1 ? c.ssim_std : c.lpips_std;
}

// Best = highest PSNR/SSIM, lowest LPIPS, compared at the printed precision so ties are all bold.
std::vector<std::vector<bool>> best_flags(const LeaderboardTable& t) {
  const auto cols = columns(t);
  std::vector<std::vector<bool>> best(t.methods.size(), std::vector<bool>(cols.size(), false));
  for (size_t col = 0; col < cols.size(); ++col) {
    const int k = cols[col].metric;
    std::string best_text;
    double best_v = 0;
    bool any = false;
    for (size_t m = 0; m < t.methods.size(); ++m) {
      const CellStats& c = cell(t, m, col);
      if (!present(c, k) || is_reference(t, m) || !cell_marks(c).empty()) continue;
      double v = value(c, k);
      if (!any || (kHigherBetter[k] ? v > best_v : v < best_v)) best_v = v;
      any = true;
    }
    if (!any) continue;
    best_text = format_metric(best_v, kDecimals[k]);
    for (size_t m = 0; m < t.methods.size(); ++m) {
      const CellStats& c = cell(t, m, col);
      best[m][col] = present(c, k) && !is_reference(t, m) && cell_marks(c).empty() &&
                     format_metric(value(c, k), kDecimals[k]) == best_text;
    }
  }
  return best;
}

std::string cell_text(const LeaderboardTable& t, const CellStats& c, int k, const char* pm) {
  if (!present(c, k)) return "";
  std::string s = format_metric(value(c, k), kDecimals[k]);
  if (c.n > 1 && std::isfinite(spread(t, c, k))) s += std::string(pm) + format_metric(spread(t, c, k), kDecimals[k]);
  return s;
}

std::string table_title(const LeaderboardTable& table) {
  if (!table.title.empty()) return table.title;
  const std::string& w = table.weather;
  if (w.empty()) return "Weather: (unspecified)";
  std::string t = w;
  t[0] = char(std::toupper(static_cast<unsigned char>(t[0])));
  return "Weather: " + t;
}

bool any_repeats(const LeaderboardTable& t) {
  for (const auto& row : t.cells)
    for (const auto& c : row)
      if (c.n > 1) return true;
  for (const auto& c : t.average)
    if (c.n > 1) return true;
  return false;
}

std::string protocol_note(const LeaderboardTable& t) {
  const bool refs = std::find(t.reference.begin(), t.reference.end(), true) != t.reference.end();
  const std::string data = other_data_note(t.data_notes) +
                           (t.recipe_notes.empty() || t.data_notes.empty() ? "" : " ") + other_recipe_note(t.recipe_notes);
  return "Protocol: " + t.protocol.to_string() + ". Best per column in bold" +
         (refs && !data.empty() ? " (reference lines and marked cells excluded)."
          : refs               ? " (reference lines excluded)."
          : !data.empty()      ? " (marked cells excluded)."
                               : ".") +
         (!any_repeats(t) ? ""
          : t.ci95 ? " Cells with repeated runs (seeds) show mean ± the half-width of its 95% Student-t interval; "
                     "an average's interval is over the seeds that ran on every scene, of each seed's mean over scenes."
                   : " Cells with repeated runs show mean ± standard deviation.") + " " + t.average_note +
         (data.empty() ? "" : " " + data);
}

void markdown(std::ostringstream& o, const LeaderboardTable& t) {
  const auto cols = columns(t);
  const auto best = best_flags(t);
  o << "## " << table_title(t) << "\n\n| Method |";
  for (const auto& c : cols) o << " " << c.group << " " << kMetricName[c.metric] << (kHigherBetter[c.metric] ? " ↑" : " ↓") << " |";
  o << "\n|---|";
  for (size_t i = 0; i < cols.size(); ++i) o << "---:|";
  o << "\n";
  for (size_t m = 0; m < t.methods.size(); ++m) {
    o << "| " << method_label(t, m) << " |";
    for (size_t col = 0; col < cols.size(); ++col) {
      std::string s = cell_text(t, cell(t, m, col), cols[col].metric, " ± ");
      if (s.empty()) s = "–";
      else if (best[m][col]) s = "**" + s + "**";
      else if (!cell_marks(cell(t, m, col)).empty()) s += " " + cell_marks(cell(t, m, col));
      o << " " << s << " |";
    }
    o << "\n";
  }
  o << "\n" << protocol_note(t) << "\n\n";
}

void csv(std::ostringstream& o, const LeaderboardTable& t, bool header) {
  const auto cols = columns(t);
  if (header) {
    o << "weather,method";
    for (const auto& c : cols) {
      std::string m = kMetricName[c.metric];
      std::transform(m.begin(), m.end(), m.begin(), ::tolower);
      o << "," << csv_escape(c.group + "_" + m);
      if (any_repeats(t)) o << "," << csv_escape(c.group + "_" + m + (t.ci95 ? "_ci95" : "_std"));
    }
    if (!t.data_notes.empty()) o << ",other_data";
    if (!t.recipe_notes.empty()) o << ",other_recipe";
    o << "\n";
  }
  for (size_t m = 0; m < t.methods.size(); ++m) {
    o << csv_escape(t.weather) << "," << csv_escape(t.methods[m]);
    for (size_t col = 0; col < cols.size(); ++col) {
      const CellStats& c = cell(t, m, col);
      const int k = cols[col].metric;
      o << "," << (present(c, k) ? format_metric(value(c, k), 6) : "");
      if (any_repeats(t)) o << "," << (present(c, k) && c.n > 1 ? format_metric(spread(t, c, k), 6) : "");
    }
    if (!t.data_notes.empty()) {  // the scenes whose cell holds results on other data, ';'-separated
      std::string scenes;
      for (size_t s = 0; s < t.scenes.size(); ++s)
        if (t.cells[m][s].other_data) scenes += (scenes.empty() ? "" : ";") + t.scenes[s];
      o << "," << csv_escape(scenes);
    }
    if (!t.recipe_notes.empty()) {  // the same for results made with another recipe
      std::string scenes;
      for (size_t s = 0; s < t.scenes.size(); ++s)
        if (t.cells[m][s].other_recipe) scenes += (scenes.empty() ? "" : ";") + t.scenes[s];
      o << "," << csv_escape(scenes);
    }
    o << "\n";
  }
}

void latex(std::ostringstream& o, const LeaderboardTable& t) {
  const auto cols = columns(t);
  const auto best = best_flags(t);
  const size_t groups = t.scenes.size() + 1;
  o << "% " << table_title(t) << ". " << protocol_note(t) << "\n";
  o << "\\begin{table}[t]\n\\centering\n\\caption{" << latex_escape(table_title(t)) << "}\n";
  o << "\\resizebox{\\linewidth}{!}{%\n\\begin{tabular}{l" << std::string(cols.size(), 'c') << "}\n\\toprule\n";
  o << "Method";
  for (size_t g = 0; g < groups; ++g)
    o << " & \\multicolumn{3}{c}{" << latex_escape(g < t.scenes.size() ? t.scenes[g] : t.average_label) << "}";
  o << " \\\\\n";
  for (size_t g = 0; g < groups; ++g) o << "\\cmidrule(lr){" << 2 + 3 * g << "-" << 4 + 3 * g << "}";
  o << "\n";
  for (size_t g = 0; g < groups; ++g) o << " & PSNR$\\uparrow$ & SSIM$\\uparrow$ & LPIPS$\\downarrow$";
  o << " \\\\\n\\midrule\n";
  for (size_t m = 0; m < t.methods.size(); ++m) {
    o << latex_escape(method_label(t, m));
    for (size_t col = 0; col < cols.size(); ++col) {
      std::string s = cell_text(t, cell(t, m, col), cols[col].metric, "$\\pm$");
      if (s == "+inf") s = "$+\\infty$";
      if (s.empty()) s = "--";
      else if (best[m][col]) s = "\\textbf{" + s + "}";
      else if (!cell_marks(cell(t, m, col)).empty())
        s += std::string("$^") + (cell(t, m, col).other_data && cell(t, m, col).other_recipe ? "{\\dagger\\ddagger}"
                                  : cell(t, m, col).other_data                             ? "\\dagger"
                                                                                           : "\\ddagger") + "$";
      o << " & " << s;
    }
    o << " \\\\\n";
  }
  o << "\\bottomrule\n\\end{tabular}}\n";
  if (!t.data_notes.empty()) {
    std::string note = other_data_note(t.data_notes);
    note.replace(0, std::string(kOtherDataMarker).size(), "");
    o << "{\\footnotesize $^\\dagger$" << latex_escape(note) << "}\n";
  }
  if (!t.recipe_notes.empty()) {
    std::string note = other_recipe_note(t.recipe_notes);
    note.replace(0, std::string(kOtherRecipeMarker).size(), "");
    o << "{\\footnotesize $^\\ddagger$" << latex_escape(note) << "}\n";
  }
  o << "\\end{table}\n\n";
}

void html(std::ostringstream& o, const LeaderboardTable& t) {
  const auto cols = columns(t);
  const auto best = best_flags(t);
  o << "<h2>" << html_escape(table_title(t)) << "</h2>\n<table>\n<thead>\n<tr><th rowspan=\"2\">Method</th>";
  for (size_t g = 0; g <= t.scenes.size(); ++g)
    o << "<th colspan=\"3\" class=\"group\">" << html_escape(g < t.scenes.size() ? t.scenes[g] : t.average_label) << "</th>";
  o << "</tr>\n<tr>";
  for (const auto& c : cols)
    o << "<th>" << kMetricName[c.metric] << (kHigherBetter[c.metric] ? "&thinsp;&uarr;" : "&thinsp;&darr;") << "</th>";
  o << "</tr>\n</thead>\n<tbody>\n";
  for (size_t m = 0; m < t.methods.size(); ++m) {
    o << "<tr><td class=\"method\">" << html_escape(method_label(t, m)) << "</td>";
    for (size_t col = 0; col < cols.size(); ++col) {
      std::string s = cell_text(t, cell(t, m, col), cols[col].metric, " &plusmn; ");
      if (s.empty()) s = "&ndash;";
      else if (!best[m][col]) {
        if (cell(t, m, col).other_data) s += " &dagger;";
        if (cell(t, m, col).other_recipe) s += " &Dagger;";
      }
      o << (cols[col].metric == 0 ? "<td class=\"first\">" : "<td>") << (best[m][col] ? "<b>" + s + "</b>" : s) << "</td>";
    }
    o << "</tr>\n";
  }
  o << "</tbody>\n</table>\n<p class=\"note\">" << html_escape(protocol_note(t)) << "</p>\n";
}

}  // namespace

void check_note(TableFormat format, const std::string& note) {
  // CSV holds data only: a comment line would be a row to a plain CSV reader.
  if (format == TableFormat::kCsv && !note.empty())
    throw InputError("--note", "a CSV table holds data only, with no place for a note: use --format md, latex or html");
}

std::string document_begin(TableFormat format, const std::string& title, const std::string& note) {
  check_note(format, note);
  switch (format) {
    case TableFormat::kMarkdown: return "# " + title + "\n\n" + (note.empty() ? "" : note + "\n\n");
    case TableFormat::kCsv: return "";
    case TableFormat::kLatex: {
      std::string comment;  // a comment, so that \\input-ing the tables into a paper prints nothing more
      std::istringstream lines(note);
      for (std::string line; std::getline(lines, line);) comment += "% " + line + "\n";
      return "% " + title + ". Generated by weathergs leaderboard; needs \\usepackage{booktabs,graphicx}\n" + comment;
    }
    case TableFormat::kHtml:
      return "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>weathergs " +
             html_escape(title) + "</title>\n"
             "<style>\nbody{font-family:system-ui,sans-serif;margin:2em;color:#222}\n"
             "table{border-collapse:collapse;margin-bottom:0.5em}\n"
             "th,td{padding:4px 8px;text-align:right;font-variant-numeric:tabular-nums}\n"
             "thead th{border-bottom:1px solid #444}th.group{border-bottom:1px solid #999}\n"
             "td.method,th[rowspan]{text-align:left}td.first,th.group{border-left:1px solid #ccc}\n"
             "tbody tr:nth-child(even){background:#f4f4f4}p.note{color:#666;font-size:0.9em}\n"
             "p.run-note{border-left:4px solid #c77c00;background:#fff6e5;padding:0.5em 0.8em;max-width:60em}\n"
             "</style>\n</head>\n<body>\n<h1>" + html_escape(title) + "</h1>\n" +
             (note.empty() ? "" : "<p class=\"run-note\">" + html_escape(note) + "</p>\n");
  }
  return "";
}

std::string document_end(TableFormat format) { return format == TableFormat::kHtml ? "</body>\n</html>\n" : ""; }

std::string render_table(const LeaderboardTable& t, TableFormat format, bool csv_header) {
  std::ostringstream o;
  switch (format) {
    case TableFormat::kMarkdown: markdown(o, t); break;
    case TableFormat::kCsv: csv(o, t, csv_header); break;
    case TableFormat::kLatex: latex(o, t); break;
    case TableFormat::kHtml: html(o, t); break;
  }
  return o.str();
}

std::string render_leaderboard(const std::vector<LeaderboardTable>& tables, TableFormat format, const std::string& note) {
  std::string o = document_begin(format, "Leaderboard", note);
  for (size_t i = 0; i < tables.size(); ++i) {
    if (i && format == TableFormat::kCsv) o += "\n";
    o += render_table(tables[i], format, true);
  }
  return o + document_end(format);
}

}  // namespace weathergs::evaluator
