#include "methods/archive_restore.h"

#include <filesystem>

#include "core/atomic_file.h"
#include "core/dataset.h"
#include "evaluator/archive.h"
#include "methods/recipe.h"

namespace weathergs::methods {

namespace fs = std::filesystem;

RestoreOutcome restore_from_archive(const ReconstructOptions& o, const std::string& suite_dir) {
  o.validate();
  const Dataset ds = read_dataset(o.dataset);
  const std::string dataset_sha256 = evaluator::identify_dataset(ds, false).sha256;
  const Json recipe = run_recipe(o, ds, dataset_sha256);
  const evaluator::ArchiveCell cell{ds.info.name, spec(o.method).name, int(o.train.seed)};
  RestoreOutcome out;
  out.cell_dir = cell.dir(suite_dir);
  const std::optional<evaluator::ArchivedRun> run = evaluator::read_archived_run(suite_dir, cell);
  if (!run) {
    out.why = "no run archived in " + out.cell_dir;
    return out;
  }
  if (run->recipe.fingerprint != evaluator::recipe_fingerprint(recipe)) {
    out.why = "the archived run was made with another recipe (" +
              evaluator::first_recipe_difference(run->recipe.recipe, recipe)->to_string() + ")";
    return out;
  }
  const fs::path dest(o.out);
  if (fs::exists(dest / evaluator::kArchiveResultsFile) && !o.force)
    throw InputError(o.out, "already holds a complete run (results.json): pass --force to replace it");
  if (o.force) fs::remove_all(dest);
  // results.json last: its presence means the run is complete (reconstruct.h).
  for (const char* f : {evaluator::kArchiveCurveFile, evaluator::kArchiveProvenanceFile, evaluator::kArchiveResultsFile})
    write_file_atomic((dest / f).string(), read_file((fs::path(out.cell_dir) / f).string()));
  out.restored = true;
  return out;
}

}  // namespace weathergs::methods
