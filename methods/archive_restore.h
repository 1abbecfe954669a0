// A run restored from the results archive (evaluator/archive.h, docs/archive.md) instead of trained:
// `reconstruct --archive DIR` asks the archive for the run its options would make, by the recipe
// they give on this dataset (methods/recipe.h), before any stage.
#pragma once

#include <string>

#include "methods/reconstruct.h"

namespace weathergs::methods {

struct RestoreOutcome {
  bool restored = false;
  std::string cell_dir;  // the archived run's folder (restored or looked at)
  std::string why;       // not restored: why ("no run archived in ...", or the first differing recipe key)
};

// When the archive `suite_dir` (<root>/<suite>) holds the run of `options`' cell (variant: the
// dataset's name; the method; train.seed) with the recipe `options` give on their dataset, writes its
// results.json, curve.json and provenance.json into options.out, byte for byte, and says so; else
// writes nothing and says why. Trains nothing. The same refusals as reconstruct before any work: a
// dataset changed since its identity was recorded, a complete run at options.out unless force, a
// missing weight file.
RestoreOutcome restore_from_archive(const ReconstructOptions& options, const std::string& suite_dir);

}  // namespace weathergs::methods
