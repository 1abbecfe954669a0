#include "evaluator/report.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "core/dataset_identity.h"
#include "core/image.h"
#include "core/json_reader.h"
#include "core/version.h"
#include "evaluator/archive.h"
#include "evaluator/paper_tables.h"
#include "evaluator/recipe.h"
#include "evaluator/report_assets.h"

namespace weathergs::evaluator {

namespace fs = std::filesystem;

void ReportOptions::validate() const {
  if (suite_dir.empty()) throw InputError("report options", "suite_dir is empty: the suite folder is required");
  if (out_dir.empty()) throw InputError("report options", "out_dir is empty: the report folder is required");
  if (thumb_width < 16 || thumb_width > 4096)
    throw InputError("report options", "thumb_width " + std::to_string(thumb_width) + " must be in 16..4096");
}

double confidence_half_width_95(int n, double sample_std) {
  if (n < 2) return 0;
  // Student's t, two-sided 95% (0.975 quantile), for 1..30 degrees of freedom; the normal's beyond.
  static const double t[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
                             2.201,  2.179, 2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086,
                             2.080,  2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042};
  const int df = n - 1;
  return (df <= 30 ? t[df - 1] : 1.960) * sample_std / std::sqrt(double(n));
}

namespace {

// One run of the suite: runs/<variant>/<method>/seed<S>/.
struct Run {
  std::string variant, method, column;  // column: "<method>/seed<S>"
  int seed = 0;
  fs::path dir;
  LoadedResults results;
  // Whether the run kept its test renders; a run restored from the results archive has none
  // (docs/archive.md): its numbers are shown, its images are not.
  bool renders = false;
};

// A results archive's suite folder: <variant>/<method>/seed<S>/ with no runs/ and no data/.
bool is_archive_suite(const fs::path& dir) {
  return fs::is_directory(dir) && !fs::exists(dir / "runs") && !fs::exists(dir / "data");
}

// Every complete run under <runs>/<variant>/<method>/seed<S>/results.json (none: empty), of the
// variants in `only` where given.
std::vector<Run> collect_runs(const fs::path& runs, const std::set<std::string>* only = nullptr) {
  std::vector<Run> out;
  std::vector<fs::path> variants;
  for (const auto& v : fs::directory_iterator(runs))
    if (v.is_directory() && (!only || only->count(v.path().filename().string()))) variants.push_back(v.path());
  std::sort(variants.begin(), variants.end());
  for (const fs::path& v : variants) {
    std::vector<fs::path> methods;
    for (const auto& m : fs::directory_iterator(v))
      if (m.is_directory()) methods.push_back(m.path());
    std::sort(methods.begin(), methods.end());
    for (const fs::path& m : methods) {
      std::vector<std::pair<int, fs::path>> seeds;
      for (const auto& s : fs::directory_iterator(m)) {
        const std::string name = s.path().filename().string();
        if (!s.is_directory() || name.rfind("seed", 0) != 0 || !fs::exists(s.path() / "results.json")) continue;
        try {
          seeds.emplace_back(std::stoi(name.substr(4)), s.path());
        } catch (const std::exception&) {
          throw InputError(s.path().string(), "expected a folder named seed<N>");
        }
      }
      std::sort(seeds.begin(), seeds.end());
      for (const auto& [seed, dir] : seeds) {
        Run r;
        r.variant = v.filename().string();
        r.method = m.filename().string();
        r.seed = seed;
        r.column = r.method + "/seed" + std::to_string(seed);
        r.dir = dir;
        r.results = {(dir / "results.json").string(), read_results((dir / "results.json").string())};
        r.renders = fs::is_directory(dir / "renders" / "test");
        out.push_back(std::move(r));
      }
    }
  }
  return out;
}

// A suite's runs: <suite>/runs/<variant>/<method>/seed<S>/, or, in a results archive's suite folder
// (`archive` set), <suite>/<variant>/<method>/seed<S>/.
std::vector<Run> find_runs(const fs::path& suite, bool* archive) {
  *archive = is_archive_suite(suite);
  const fs::path runs = *archive ? suite : suite / "runs";
  if (!fs::is_directory(runs))
    throw InputError(runs.string(), "missing: a suite folder has runs/<variant>/<method>/seed<S>/ (a results archive's "
                                    "suite folder, <variant>/<method>/seed<S>/)");
  std::vector<Run> out = collect_runs(runs);
  if (out.empty())
    throw InputError(runs.string(), std::string("holds no complete run (") +
                                        (*archive ? "<variant>" : "runs/<variant>") + "/<method>/seed<S>/results.json)");
  return out;
}

// A JSON number, or null for NaN / infinity (JSON has neither).
Json number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

std::string fixed(double v, int decimals) {
  if (std::isinf(v) && v > 0) return "+inf";
  if (!std::isfinite(v)) return "–";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

// "24.98 ± 0.31" over n seeds (the 95% interval), "24.98" for one.
Json stat_cell(double mean, double population_std, int n, int decimals, const std::string& link) {
  if (n == 0) return Json{{"text", "–"}};
  const double sample = n > 1 ? population_std * std::sqrt(double(n) / double(n - 1)) : 0;
  const double half = confidence_half_width_95(n, sample);
  Json c{{"text", fixed(mean, decimals) + (n > 1 ? " ± " + fixed(half, decimals) : "")}, {"value", number(mean)}, {"n", n}};
  if (n > 1) c["ci95"] = number(half);
  if (!link.empty()) c["link"] = link;
  return c;
}

// (scene, weather) of the results -> the runs/<variant>/ folder that holds them.
using VariantOf = std::map<std::pair<std::string, std::string>, std::string>;

// A cell's text with the markers of the runs on other data or of other recipes it holds.
Json marked(Json cell, const CellStats& s) {
  if (!cell_marks(s).empty()) cell["text"] = cell["text"].get<std::string>() + " " + cell_marks(s);
  return cell;
}

// to_runs: the relative path from the report to the folder of the runs' variants.
Json quality_table(const LeaderboardTable& t, const std::string& id, const std::string& to_runs, const VariantOf* variant_of) {
  Json columns = Json::array({{{"key", "method"}, {"label", "method"}}});
  std::vector<std::string> groups = t.scenes;
  groups.push_back(t.average_label);
  for (const std::string& g : groups)
    for (const auto& [m, label, better] : {std::tuple<const char*, const char*, const char*>{"psnr", "PSNR ↑", "higher"},
                                           {"ssim", "SSIM ↑", "higher"},
                                           {"lpips", "LPIPS ↓", "lower"}})
      columns.push_back({{"key", g + "." + m}, {"label", g + " " + label}, {"better", better}});
  Json rows = Json::array();
  for (size_t mi = 0; mi < t.methods.size(); ++mi) {
    const std::string& method = t.methods[mi];
    const bool ref = mi < t.reference.size() && t.reference[mi];
    Json cells{{"method", {{"text", method}}}};  // the page marks reference rows itself
    for (size_t g = 0; g < groups.size(); ++g) {
      const bool avg = g == t.scenes.size();
      const CellStats& s = avg ? t.average[mi] : t.cells[mi][g];
      std::string link;
      if (!avg && variant_of && s.n > 0)
        if (auto it = variant_of->find({t.scenes[g], t.weather}); it != variant_of->end())
          link = to_runs + it->second + "/" + method + "/";
      cells[groups[g] + ".psnr"] = marked(stat_cell(s.psnr, s.psnr_std, s.n, 2, link), s);
      cells[groups[g] + ".ssim"] = marked(stat_cell(s.ssim, s.ssim_std, s.n, 4, link), s);
      cells[groups[g] + ".lpips"] =
          s.has_lpips ? marked(stat_cell(s.lpips, s.lpips_std, s.n, 4, link), s) : Json{{"text", "–"}};
    }
    rows.push_back({{"method", method}, {"reference", ref}, {"cells", cells}});
  }
  const std::string data = other_data_note(t.data_notes) +
                           (t.recipe_notes.empty() || t.data_notes.empty() ? "" : " ") + other_recipe_note(t.recipe_notes);
  return {{"id", id},
          {"title", t.title.empty() ? "Weather: " + t.weather : t.title},
          {"note", t.average_note + " Cells over several seeds show mean ± the 95% confidence interval (Student's t)." +
                       (data.empty() ? "" : " " + data)},
          {"columns", columns},
          {"rows", rows}};
}

Json cost_table(const std::vector<CostRow>& cost) {
  Json columns = Json::array({{{"key", "method"}, {"label", "method"}},
                              {{"key", "train_seconds"}, {"label", "training (s)"}, {"better", "lower"}},
                              {{"key", "train_cpu_seconds"}, {"label", "training CPU (s)"}, {"better", "lower"}},
                              {{"key", "restoration_seconds"}, {"label", "AEF + LED (s)"}, {"better", "lower"}},
                              {{"key", "render_ms_per_view"}, {"label", "render (ms/view)"}, {"better", "lower"}},
                              {{"key", "peak_rss_mb"}, {"label", "peak memory (MiB)"}, {"better", "lower"}},
                              {{"key", "gaussians"}, {"label", "Gaussians"}},
                              {{"key", "runs"}, {"label", "runs"}}});
  Json rows = Json::array();
  for (const CostRow& c : cost) {
    auto cell = [](double v, int d) { return Json{{"text", fixed(v, d)}, {"value", number(v)}}; };
    rows.push_back({{"method", c.method},
                    {"reference", c.reference},
                    {"cells",
                     {{"method", {{"text", c.method}}},
                      {"train_seconds", cell(c.train_seconds, 1)},
                      {"train_cpu_seconds", cell(c.train_cpu_seconds, 1)},
                      {"restoration_seconds", cell(c.restoration_seconds, 1)},
                      {"render_ms_per_view", cell(c.render_ms_per_view, 1)},
                      {"peak_rss_mb", cell(c.peak_rss_mb, 0)},
                      {"gaussians", cell(c.gaussians, 0)},
                      {"runs", {{"text", std::to_string(c.runs)}, {"value", c.runs}}}}}});
  }
  return {{"columns", columns}, {"rows", rows}};
}

// 8-bit BGR(A) of an sRGB image (1..4 channels).
cv::Mat to_mat8(const Image& img) {
  const Image rgb = to_srgb(to_rgb(img));
  cv::Mat m(rgb.height, rgb.width, CV_8UC3);
  for (int y = 0; y < rgb.height; ++y)
    for (int x = 0; x < rgb.width; ++x)
      for (int c = 0; c < 3; ++c)
        m.at<cv::Vec3b>(y, x)[2 - c] = cv::saturate_cast<uchar>(std::lround(255.f * std::clamp(rgb.at(x, y, c), 0.f, 1.f)));
  return m;
}

void write_mat(const fs::path& path, const cv::Mat& m) {
  const std::vector<int> params = path.extension() == ".jpg" ? std::vector<int>{cv::IMWRITE_JPEG_QUALITY, 88} : std::vector<int>{};
  if (!cv::imwrite(path.string(), m, params)) throw InputError(path.string(), "cannot write the image");
}

cv::Mat thumbnail(const cv::Mat& m, int width) {
  if (m.cols <= width) return m;
  cv::Mat t;
  cv::resize(m, t, cv::Size(width, std::max(1, int(std::lround(double(m.rows) * width / m.cols)))), 0, 0, cv::INTER_AREA);
  return t;
}

// |render - truth| per pixel, averaged over channels, 4x amplified, as a heat map.
cv::Mat difference(const cv::Mat& a, const cv::Mat& truth, const std::string& where) {
  if (a.size() != truth.size())
    throw InputError(where, "is " + std::to_string(a.cols) + "x" + std::to_string(a.rows) + ", the ground truth " +
                                std::to_string(truth.cols) + "x" + std::to_string(truth.rows));
  cv::Mat d, gray, heat;
  cv::absdiff(a, truth, d);
  cv::cvtColor(d, gray, cv::COLOR_BGR2GRAY);
  gray.convertTo(gray, CV_8U, 4.0);
  cv::applyColorMap(gray, heat, cv::COLORMAP_INFERNO);
  return heat;
}

// A mask (255 = the effect) as an RGBA overlay in `bgr`, transparent elsewhere.
void write_overlay(const fs::path& path, const std::string& mask_path, const cv::Vec3b& bgr, int width, int height) {
  const Image mask = read_mask(mask_path);
  if (mask.width != width || mask.height != height)
    throw InputError(mask_path, "is " + mask.to_string() + ", the view " + std::to_string(width) + "x" + std::to_string(height));
  cv::Mat m(height, width, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      if (mask.at(x, y) >= 0.5f) m.at<cv::Vec4b>(y, x) = {bgr[0], bgr[1], bgr[2], 150};
  write_mat(path, m);
}

std::string file_safe(std::string s) {
  std::replace(s.begin(), s.end(), '/', '_');
  return s;
}

int64_t folder_bytes(const fs::path& dir) {
  int64_t n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.is_regular_file()) n += int64_t(e.file_size());
  return n;
}

Json metrics_json(const MetricValues& m) {
  return {{"psnr", number(m.psnr)}, {"ssim", number(m.ssim)}, {"lpips", m.lpips ? number(*m.lpips) : Json(nullptr)}};
}

// "1 run", "2 runs".
std::string counted(size_t n, const std::string& noun) { return std::to_string(n) + " " + noun + (n == 1 ? "" : "s"); }

std::string joined(const std::set<std::string>& names) {
  std::string out;
  for (const std::string& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

// The results archive's runs of the suite's variants (ReportOptions::converged_dir) as a section of
// their own: a table holds one recipe, and the archive's (the fast schedule) is not the suite's.
// suite_identity: variant -> the sha256 of the suite's data/<variant>, where the suite has one.
Json converged_section(const ReportOptions& o, const fs::path& final_out, const std::set<std::string>& variants,
                       const std::map<std::string, std::string>& suite_identity, const LeaderboardOptions& board,
                       int* shown) {
  const fs::path dir = fs::absolute(o.converged_dir).lexically_normal();
  if (!fs::is_directory(dir))
    throw InputError(o.converged_dir, "missing: --converged expects a results archive's suite folder (<root>/<suite>, "
                                      "e.g. benchmarks/results/quick)");
  if (!is_archive_suite(dir))
    throw InputError(o.converged_dir, "holds runs/ or data/: a suite folder, not a results archive's suite folder "
                                      "(<variant>/<method>/seed<S>/; docs/archive.md)");
  const std::vector<Run> runs = collect_runs(dir, &variants);
  *shown = int(runs.size());
  std::string link = fs::relative(dir, final_out).generic_string();  // relative: the two can move together
  link = link.empty() || link == "." ? "" : link + "/";
  Json c{{"path", o.converged_dir}, {"link", link}, {"variants", Json(std::vector<std::string>(variants.begin(), variants.end()))},
         {"runs", runs.size()}, {"tables", Json::array()}};
  Json lines = Json::array();

  // How far the archive's matrix is: cells that hold a run (whether each is current with this build's
  // recipes is `weathergs archive status`'s to say: it needs the methods' weights and datasets).
  const fs::path matrix_path = dir / "matrix.json";
  std::string matrix_line;
  if (fs::exists(matrix_path)) {
    const ArchiveMatrix m = read_archive_matrix(matrix_path.string());
    int archived = 0, variant_cells = 0, variant_archived = 0;
    for (const ArchiveCell& cell : m.cells) {
      const bool held = fs::exists(fs::path(cell.dir(dir.string())) / kArchiveResultsFile);
      archived += held;
      if (variants.count(cell.variant)) {
        ++variant_cells;
        variant_archived += held;
      }
    }
    c["matrix"] = {{"cells", m.cells.size()}, {"archived", archived}, {"variant_cells", variant_cells},
                   {"variant_archived", variant_archived}};
    matrix_line = "Its matrix (matrix.json): " + std::to_string(archived) + " of " + std::to_string(m.cells.size()) +
                  " cells archived; " + std::to_string(variant_archived) + " of the " + std::to_string(variant_cells) +
                  " on " + joined(variants) + ". Which are current with this build's recipes: weathergs archive status.";
  }
  if (runs.empty()) {
    c["message"] = "The results archive " + o.converged_dir + " holds no run of " + joined(variants) +
                   " yet: no converged tables to show.";
    if (!matrix_line.empty()) lines.push_back(matrix_line);
    c["lines"] = lines;
    return c;
  }
  std::vector<LoadedResults> loaded;
  for (const Run& r : runs) loaded.push_back(r.results);
  const PaperTables paper = build_paper_tables(loaded, board);  // the archive's own runs must agree
  std::set<std::string> methods, held, lacking = variants;
  for (const Run& r : runs) {
    methods.insert(r.method);
    held.insert(r.variant);
    lacking.erase(r.variant);
  }
  lines.push_back("The runs of the results archive " + o.converged_dir + " on " + joined(held) + ": " +
                  counted(runs.size(), "run") + " of " + counted(methods.size(), "method") +
                  (lacking.empty() ? "" : " (none yet on " + joined(lacking) + ")") +
                  ". Tables of their own, never mixed into this suite's rows: one table holds one recipe "
                  "(docs/archive.md).");
  if (!matrix_line.empty()) lines.push_back(matrix_line);
  // Whether the archive's numbers were scored on the very datasets this suite's were.
  std::map<std::string, std::string> archive_identity;  // variant -> the first run's recorded identity
  for (const Run& r : runs)
    if (!archive_identity.count(r.variant))
      archive_identity[r.variant] = r.results.results.dataset_identity ? r.results.results.dataset_identity->sha256 : "";
  std::string same, other;
  for (const auto& [variant, id] : archive_identity) {
    const auto it = suite_identity.find(variant);
    if (it == suite_identity.end() || id.empty()) continue;
    if (id == it->second) same += (same.empty() ? "" : ", ") + variant;
    else other += (other.empty() ? "" : "; ") + variant + " (" + id.substr(0, 12) + " against " + it->second.substr(0, 12) + ")";
  }
  if (!same.empty()) lines.push_back("Scored on the same datasets as this suite's: " + same + ".");
  if (!other.empty()) lines.push_back("Scored on other datasets than this suite's: " + other + ".");
  VariantOf variant_of;
  for (const Run& r : runs) variant_of[{r.results.results.scene, r.results.results.weather}] = r.variant;
  int ti = 0;
  for (const LeaderboardTable& t : paper.quality)
    c["tables"].push_back(quality_table(t, "converged-table-" + std::to_string(++ti), link, &variant_of));
  if (!paper.ablation.methods.empty())
    c["tables"].push_back(quality_table(paper.ablation, "converged-table-ablation", link, nullptr));
  c["cost"] = cost_table(paper.cost);
  c["lines"] = lines;
  return c;
}

}  // namespace

ReportSummary write_report(const ReportOptions& o) {
  o.validate();
  const fs::path suite = fs::absolute(o.suite_dir).lexically_normal();
  check_writable_destination(o.out_dir, "the report folder (-o)");
  bool archive = false;  // a results archive's suite folder: the runs' numbers, no images
  const std::vector<Run> runs = find_runs(suite, &archive);
  std::vector<LoadedResults> loaded;
  for (const Run& r : runs) loaded.push_back(r.results);
  LeaderboardOptions board;
  board.allow_mixed_data = o.allow_mixed_data;
  board.allow_mixed_recipes = o.allow_mixed_recipes;
  // Also checks that the protocols agree, and that each variant's runs were scored on one dataset.
  const PaperTables paper = build_paper_tables(loaded, board);
  // The page shows data/<variant>'s inputs and truth beside each run: a run that records its dataset's
  // identity must have been scored on those very files.
  std::map<std::string, std::string> data_identity;  // variant -> sha256 of data/<variant>
  std::set<const Run*> other_data;  // marked: on other data than their variant's runs or data/<variant>
  const MixedData mixed = find_mixed_data(loaded, board);
  for (size_t i = 0; i < runs.size(); ++i)
    if (mixed.is_odd(loaded[i])) other_data.insert(&runs[i]);
  const MixedRecipes recipes = find_mixed_recipes(loaded, board);
  for (const Run& r : runs) {
    const fs::path data = suite / "data" / r.variant;
    if (!fs::exists(data / "dataset.json")) continue;  // refused below, naming the variant
    if (!data_identity.count(r.variant)) data_identity[r.variant] = compute_dataset_identity(data.string()).sha256;
    const std::optional<ScoredDataset>& scored = r.results.results.dataset_identity;
    if (!scored || scored->sha256 == data_identity[r.variant]) continue;
    if (!o.allow_mixed_data)
      throw InputError(r.results.path, "scored on other data (dataset identity " + scored->sha256 + ") than " +
                                           data.string() + " (" + data_identity[r.variant] +
                                           "), which the report shows beside it: re-run it on that dataset, or pass "
                                           "--allow-mixed-data to mark it");
    other_data.insert(&r);
  }

  // Links from the report into the suite (the runs' folders), relative so that both can move together.
  const fs::path final_out = fs::absolute(o.out_dir).lexically_normal();
  ReportSummary summary;
  Json converged;  // read before anything is written: a bad archive leaves nothing
  if (!o.converged_dir.empty()) {
    std::set<std::string> variants;
    for (const Run& r : runs) variants.insert(r.variant);
    converged = converged_section(o, final_out, variants, data_identity, board, &summary.converged_runs);
  }

  AtomicDirectory dir(o.out_dir);
  const fs::path out(dir.path());
  std::string to_suite = fs::relative(suite, final_out).generic_string();
  to_suite = to_suite.empty() || to_suite == "." ? "" : to_suite + "/";

  Json report{{"format", "weathergs-report"}, {"version", 1}, {"title", "weathergs results: " + suite.filename().string()}};
  if (!o.note.empty()) report["note"] = o.note;
  if (!converged.is_null()) report["converged"] = converged;
  Json tables = Json::array();
  int ti = 0;
  VariantOf variant_of;
  for (const Run& r : runs) variant_of[{r.results.results.scene, r.results.results.weather}] = r.variant;
  const std::string to_runs = to_suite + (archive ? "" : "runs/");
  for (const LeaderboardTable& t : paper.quality)
    tables.push_back(quality_table(t, "table-" + std::to_string(++ti), to_runs, &variant_of));
  if (!paper.ablation.methods.empty()) tables.push_back(quality_table(paper.ablation, "table-ablation", to_runs, nullptr));
  report["tables"] = tables;
  report["cost"] = cost_table(paper.cost);

  // Per variant: the test views, one column per input, run and truth.
  std::map<std::string, std::vector<const Run*>> by_variant;
  for (const Run& r : runs) by_variant[r.variant].push_back(&r);
  Json variants = Json::array(), datasets = Json::array();
  for (auto& [variant, all_runs] : by_variant) {
    std::vector<const Run*> vruns;  // the columns: runs with their renders
    Json without_renders = Json::array();
    for (const Run* r : all_runs)
      if (r->renders) vruns.push_back(r);
      else without_renders.push_back(r->method + " (seed " + std::to_string(r->seed) + ")");
    std::stable_partition(vruns.begin(), vruns.end(), [](const Run* r) { return !is_reference_method(r->method); });
    ++summary.variants;
    if (archive) {  // no datasets beside the records: the identity the runs record
      const std::optional<ScoredDataset>& id = all_runs.front()->results.results.dataset_identity;
      datasets.push_back({{"name", variant},
                          {"ground_truth_sha256", all_runs.front()->results.results.sha256_ground_truth},
                          {"dataset_identity", id ? Json(id->sha256) : Json()}});
      continue;
    }
    const fs::path data = suite / "data" / variant;
    if (!fs::exists(data / "dataset.json"))
      throw InputError(data.string(), "missing: the dataset of variant " + variant + " (the report shows its inputs and truth)");
    const Dataset ds = read_dataset(data.string());
    const std::vector<std::string>& views = ds.split("test");
    Json columns = Json::array({{{"id", "input"}, {"label", "weathered input"}, {"kind", "input"}}});
    for (const Run* r : vruns)
      columns.push_back({{"id", r->column},
                         {"label", r->method + " (seed " + std::to_string(r->seed) + ")" +
                                       (other_data.count(r) ? std::string(" ") + kOtherDataMarker : "") +
                                       (recipes.is_odd(loaded[size_t(r - runs.data())]) ? std::string(" ") + kOtherRecipeMarker : "")},
                         {"kind", "method"},
                         {"method", r->method},
                         {"seed", r->seed},
                         {"other_data", other_data.count(r) > 0},
                         {"run", to_suite + fs::relative(r->dir, suite).generic_string() + "/"}});
    columns.push_back({{"id", "gt"}, {"label", "ground truth"}, {"kind", "truth"}});
    Json overlays = Json::array();
    const bool has_lens = ds.has(ImageKind::kLensMask), has_particles = ds.has(ImageKind::kParticleMask);
    if (has_lens) overlays.push_back({{"id", "lens"}, {"label", "lens drops (truth)"}});
    if (has_particles) overlays.push_back({{"id", "particles"}, {"label", "particles (truth)"}});
    std::vector<const Run*> led_runs;
    for (const Run* r : vruns)
      if (fs::exists(r->dir / "detected")) {
        led_runs.push_back(r);
        overlays.push_back({{"id", "led:" + r->column}, {"label", "LED mask used by " + r->column}});
      }
    Json jviews = Json::array();
    for (const std::string& v : views) {
      const fs::path img = out / "img" / variant / v;
      fs::create_directories(img);
      const std::string rel = "img/" + variant + "/" + v + "/";
      const cv::Mat truth = to_mat8(read_image(ds.path(ImageKind::kClean, v)));
      Json cells = Json::object();
      auto add = [&](const std::string& id, const fs::path& source, const MetricValues* m) {
        const cv::Mat im = to_mat8(read_image(source.string()));
        const std::string stem = file_safe(id);
        write_mat(img / (stem + ".jpg"), thumbnail(im, o.thumb_width));
        write_mat(img / (stem + "_full.png"), im);
        Json c{{"thumb", rel + stem + ".jpg"}, {"full", rel + stem + "_full.png"}};
        if (id != "gt") {
          write_mat(img / (stem + "_diff.jpg"), thumbnail(difference(im, truth, source.string()), o.thumb_width));
          c["diff"] = rel + stem + "_diff.jpg";
        }
        if (m) c["metrics"] = metrics_json(*m);
        summary.images += id == "gt" ? 2 : 3;
        cells[id] = c;
      };
      add("input", ds.path(ImageKind::kImages, v), nullptr);
      for (const Run* r : vruns) {
        const fs::path render = r->dir / "renders" / "test" / (v + ".png");
        if (!fs::exists(render)) throw InputError(render.string(), "missing: run " + r->dir.string() + " has no render of test view " + v);
        const MetricValues* m = nullptr;
        for (const auto& [name, values] : r->results.results.per_view)
          if (name == v) m = &values;
        add(r->column, render, m);
      }
      add("gt", ds.path(ImageKind::kClean, v), nullptr);
      Json jo = Json::object();
      if (has_lens && fs::exists(ds.path(ImageKind::kLensMask, v))) {
        write_overlay(img / "lens.png", ds.path(ImageKind::kLensMask, v), {60, 60, 255}, truth.cols, truth.rows);
        jo["lens"] = rel + "lens.png";
      }
      if (has_particles && fs::exists(ds.path(ImageKind::kParticleMask, v))) {
        write_overlay(img / "particles.png", ds.path(ImageKind::kParticleMask, v), {255, 160, 40}, truth.cols, truth.rows);
        jo["particles"] = rel + "particles.png";
      }
      for (const Run* r : led_runs) {
        const fs::path mask = r->dir / "detected" / (v + ".png");
        if (!fs::exists(mask)) continue;
        const std::string name = "led_" + file_safe(r->column) + ".png";
        write_overlay(img / name, mask.string(), {80, 220, 80}, truth.cols, truth.rows);
        jo["led:" + r->column] = rel + name;
      }
      jviews.push_back({{"name", v}, {"cells", cells}, {"overlays", jo}});
      ++summary.views;
    }
    const Camera& cam = ds.cameras.front();
    variants.push_back({{"name", variant},
                        {"scene", ds.info.scene},
                        {"weather", ds.info.weather},
                        {"width", cam.width},
                        {"height", cam.height},
                        {"columns", columns},
                        {"overlays", overlays},
                        {"without_renders", without_renders},
                        {"views", jviews}});
    datasets.push_back({{"name", variant},
                        {"ground_truth_sha256", all_runs.front()->results.results.sha256_ground_truth},
                        {"dataset_identity", data_identity[variant]}});
  }
  report["variants"] = variants;

  // Curves, the per-run costs and the weights every run used.
  Json curves = Json::array(), jruns = Json::array();
  std::map<std::string, std::string> weights;  // name -> sha256
  std::set<std::string> commits;
  for (size_t ri = 0; ri < runs.size(); ++ri) {
    const Run& r = runs[ri];
    const Json& mi = r.results.results.method_info;
    const std::optional<RecordedRecipe> recipe = recorded_recipe(r.results.results, r.results.path);
    const fs::path curve = r.dir / "curve.json";
    if (fs::exists(curve)) {
      Json points = Json::array();
      for (const Json& p : read_json_file(curve.string()).value("points", Json::array()))
        points.push_back({{"iteration", p.value("iteration", 0)},
                          {"train_seconds", p.value("train_seconds", 0.0)},
                          {"psnr", p.contains("psnr") ? p.at("psnr") : Json(nullptr)},
                          {"ssim", p.contains("ssim") ? p.at("ssim") : Json(nullptr)},
                          {"lpips", p.contains("lpips") ? p.at("lpips") : Json(nullptr)},
                          {"num_gaussians", p.value("num_gaussians", 0)}});
      curves.push_back({{"variant", r.variant}, {"method", r.method}, {"seed", r.seed}, {"points", points}});
    }
    jruns.push_back({{"variant", r.variant},
                     {"method", r.method},
                     {"seed", r.seed},
                     {"path", to_suite + fs::relative(r.dir, suite).generic_string() + "/"},
                     {"dataset_identity", short_dataset_identity(r.results.results)},
                     {"other_data", other_data.count(&r) > 0},
                     {"recipe", recipe ? recipe->fingerprint.substr(0, 12) : "none recorded"},
                     {"other_recipe", recipes.is_odd(loaded[ri])},
                     {"archived", !r.renders},
                     {"train_seconds", mi.value("train_seconds", Json(nullptr))},
                     {"peak_rss_mb", mi.value("peak_rss_mb", Json(nullptr))},
                     {"num_gaussians", mi.value("num_gaussians", Json(nullptr))}});
    if (mi.contains("weights") && mi.at("weights").is_object()) {
      const Json& w = mi.at("weights");
      if (w.contains("led") && w.at("led").is_string()) weights["led"] = w.at("led").get<std::string>();
      if (w.contains("aef") && w.at("aef").is_object())
        for (const auto& [stem, sha] : w.at("aef").items())
          if (sha.is_string()) weights["aef/" + stem] = sha.get<std::string>();
    }
    if (mi.contains("weathergs_commit") && mi.at("weathergs_commit").is_string())
      commits.insert(mi.at("weathergs_commit").get<std::string>());
  }
  for (const auto& [name, sha] : o.extra_weights) weights[name] = sha;
  Json jweights = Json::array();
  for (const auto& [name, sha] : weights) jweights.push_back({{"name", name}, {"sha256", sha}});
  report["curves"] = curves;
  report["runs"] = jruns;
  report["provenance"] = {{"commit", source_commit()},
                          {"run_commits", Json(std::vector<std::string>(commits.begin(), commits.end()))},
                          {"protocol", runs.front().results.results.protocol.to_string()},
                          {"command", o.command},
                          {"weights", jweights},
                          {"datasets", datasets}};
  summary.runs = int(runs.size());

  for (const ReportAsset& a : report_assets()) write_file_atomic((out / a.name).string(), a.contents);
  write_file_atomic((out / "data.js").string(), "window.WEATHERGS_REPORT = " + report.dump(1) + ";\n");
  summary.bytes = folder_bytes(out);
  dir.commit();
  summary.index = (final_out / "index.html").string();
  return summary;
}

}  // namespace weathergs::evaluator
