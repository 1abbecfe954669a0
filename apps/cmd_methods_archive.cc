// weathergs archive add|status: the results archive (evaluator/archive.h, docs/archive.md). A run is
// restored from it by `reconstruct --archive DIR` (methods/archive_restore.h).
#include <cstdio>
#include <filesystem>
#include <map>

#include "apps/command.h"
#include "apps/resources.h"
#include "core/dataset.h"
#include "evaluator/archive.h"
#include "evaluator/evaluate.h"
#include "methods/recipe.h"

namespace weathergs::cli {
namespace {

namespace fs = std::filesystem;

struct ArchiveArgs {
  std::string root, suite;
  std::vector<std::string> runs;
  std::string variant;
  bool replace = false;
  std::string matrix, data;
  std::string suite_dir() const { return (fs::path(root) / suite).string(); }
};

int run_add(const ArchiveArgs& a) {
  for (const std::string& run : a.runs) {
    evaluator::ArchiveAddOptions o;
    o.run_dir = run;
    o.suite_dir = a.suite_dir();
    o.variant = a.variant;
    o.replace = a.replace;
    const evaluator::ArchiveAddResult r = evaluator::archive_add(o);
    const char* what = r.outcome == evaluator::ArchiveAddResult::Outcome::kAdded      ? "added"
                       : r.outcome == evaluator::ArchiveAddResult::Outcome::kReplaced ? "replaced"
                                                                                      : "kept (same recipe)";
    std::printf("%s %s: %s\n", what, r.cell.to_string().c_str(), r.dir.c_str());
  }
  return kExitOk;
}

// The options a cell of the matrix runs with: the matrix's options of its backend, the installed
// weights and LPIPS model (as reconstruct finds them without flags).
methods::ReconstructOptions cell_options(const evaluator::ArchiveMatrix& m, const std::string& matrix_path,
                                         const evaluator::ArchiveCell& c) {
  methods::ReconstructOptions o;
  o.method = methods::parse_method(c.method, matrix_path + ": " + c.to_string());
  const methods::Recipe& r = methods::spec(o.method).recipe;
  static const Json kNone = Json::object();  // a JsonReader keeps a pointer to its value: never a temporary
  auto options_of = [&](const char* backend) {
    const auto it = m.options.find(backend);
    return JsonReader(it == m.options.end() ? kNone : it->second, matrix_path, std::string("/options/") + backend);
  };
  o.train = reconstruction::TrainOptions::from_user_json(options_of("3dgs"));
  o.nerf = nerf::NerfOptions::from_user_json(options_of("nerf"));
  o.train.seed = uint64_t(c.seed);
  o.scoring.lpips_model_search = lpips_model_search("");
  if (r.needs_led_weights()) o.led_weights = find_led_weights("");
  if (r.needs_aef_weights()) o.aef_weights = find_aef_weights("");
  return o;
}

int run_status(const ArchiveArgs& a) {
  const std::string matrix_path = a.matrix.empty() ? (fs::path(a.suite_dir()) / "matrix.json").string() : a.matrix;
  const evaluator::ArchiveMatrix m = evaluator::read_archive_matrix(matrix_path);
  std::map<std::string, std::optional<std::pair<Dataset, std::string>>> datasets;  // variant -> (dataset, sha256)
  const evaluator::ArchiveStatus s = evaluator::archive_status(a.suite_dir(), m, [&](const evaluator::ArchiveCell& c) {
    methods::ReconstructOptions o = cell_options(m, matrix_path, c);
    if (!datasets.count(c.variant)) {
      const fs::path dir = fs::path(a.data) / c.variant;
      datasets[c.variant] = std::nullopt;
      if (!a.data.empty() && fs::exists(dir / "dataset.json")) {
        const Dataset ds = read_dataset(dir.string());
        datasets[c.variant] = std::make_pair(ds, evaluator::identify_dataset(ds, false).sha256);
      }
    }
    const auto& d = datasets[c.variant];
    return d ? methods::run_recipe(o, d->first, d->second) : methods::run_recipe_across_datasets(o);
  });
  std::fputs(evaluator::render_archive_status(s).c_str(), stdout);
  return kExitOk;
}

Command make(CLI::App& root) {
  auto a = std::make_shared<ArchiveArgs>();
  CLI::App* sub = root.add_subcommand(
      "archive",
      "The results archive: finished runs kept in git as small records (benchmarks/results/<suite>/), so that a "
      "suite resumes on another machine (docs/archive.md). Restore a run with reconstruct --archive");
  sub->require_subcommand(1);
  auto common = [&](CLI::App* c) {
    c->add_option("--root", a->root, "The archive's root folder (benchmarks/results)")->required();
    c->add_option("--suite", a->suite, "The suite's name (its folder under --root, e.g. quick)")->required();
  };
  CLI::App* add = sub->add_subcommand(
      "add", "Copy finished runs' records (results.json, curve.json, model/run.json; a few kB, never renders or "
             "models) into <root>/<suite>/<variant>/<method>/seed<N>/ with a provenance.json");
  add->add_option("runs", a->runs, "Run folders of weathergs reconstruct")->required()->check(CLI::ExistingDirectory);
  common(add);
  add->add_option("--variant", a->variant, "The variant's folder (default: the results' dataset name, <scene>_<weather>)");
  add->add_flag("--replace", a->replace,
                "Replace an archived run of the same cell (refused, exit 2, when its recipe differs; kept when it is "
                "the same)");
  CLI::App* status = sub->add_subcommand(
      "status", "Per cell of the suite's matrix: done (with the recipe this build would use), stale (another recipe: "
                "the first differing key) or missing; totals and the CPU-hours spent and left");
  common(status);
  status->add_option("--matrix", a->matrix, "The suite's cells (default: <root>/<suite>/matrix.json)")
      ->check(CLI::ExistingFile);
  status->add_option("--data", a->data,
                     "The folder of the suite's datasets (<data>/<variant>/, the workflow's OUT/data): checks the "
                     "runs' dataset identities and run lengths too; without it, the rest of their recipes");
  return {sub, [a, add] { return add->parsed() ? run_add(*a) : run_status(*a); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(archive, weathergs::cli::make)
