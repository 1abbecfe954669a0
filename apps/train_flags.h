// The 3DGS trainer's flags that `train` and `reconstruct` share, defined once so that both read,
// default and document them the same way. Flags only `train` has (its inputs, --resume) stay there.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "core/error.h"
#include "reconstruction/trainer.h"

namespace weathergs::cli {

struct TrainFlags {
  std::string random_init = "photo", mask_normalization = "valid", large_prune = "distance";
  std::vector<double> background;

  // Binds the numeric flags to `train` and `checkpoint_every`; the named choices go through apply().
  void add_to(CLI::App* app, reconstruction::TrainOptions& train, int& checkpoint_every) {
    app->add_option("--iterations", train.iterations, "3DGS training iterations")
        ->capture_default_str()->check(CLI::PositiveNumber);
    app->add_option("--seed", train.seed, "Random seed (view order, random initialization; reconstruct: the radiance field's too)")
        ->capture_default_str();
    app->add_option("--background", background, "Background colour R G B in [0, 1] (default 0 0 0)")->expected(3);
    app->add_option("--max-gaussians", train.max_gaussians,
                    "Memory guard: densification never grows the model beyond this many Gaussians (~2.6 KiB each)")
        ->capture_default_str();
    app->add_option("--random-init", random_init,
                    "Random initialization when there are no SfM points: photo (each point at the depth where "
                    "neighbouring views agree) or frustum (uniform in inverse depth, random colours)")
        ->capture_default_str()->check(CLI::IsMember({"photo", "frustum"}));
    app->add_option("--random-init-count", train.random_init_count,
                    "Gaussians of the random initialization (used when there are no SfM points)")
        ->capture_default_str();
    app->add_option("--mask-normalization", mask_normalization,
                    "Masked loss: valid (means over the valid pixels, masked ones count for nothing) or reference "
                    "(the WeatherGS release: masked target pixels replaced by the render, means over all pixels); "
                    "docs/reconstruction.md")
        ->capture_default_str()->check(CLI::IsMember({"valid", "reference"}));
    app->add_option("--large-prune", large_prune,
                    "Large-Gaussian prune (from --large-prune-from on): distance (a Gaussian may be up to "
                    "max_world_size x the larger of the cameras' extent and its distance from the rig) or "
                    "camera_extent (the reference: max_world_size x the cameras' extent; collapses forward-facing "
                    "scenes at 30,000 iterations); docs/reconstruction.md")
        ->capture_default_str()->check(CLI::IsMember({"distance", "camera_extent"}));
    app->add_option("--large-prune-from", train.large_prune_from,
                    "Iteration after which the large-Gaussian prune runs (at densification steps); the default, "
                    "the reference's first opacity reset, is scaled with --iterations like the densification window")
        ->capture_default_str()->check(CLI::NonNegativeNumber);
    app->add_option("--distractor-opacity-weight", train.distractor_opacity_weight,
                    "desplat: opacity penalty of the per-view distractor Gaussians: the loss gains this x the image "
                    "fraction their opacity covers (docs/reconstruction.md)")
        ->capture_default_str()->check(CLI::NonNegativeNumber);
    app->add_option("--checkpoint-every", checkpoint_every, "Iterations between checkpoints (0 = only at the end)")
        ->capture_default_str()->check(CLI::NonNegativeNumber);
  }

  // The named choices and the background, after parsing.
  void apply(reconstruction::TrainOptions& train) const {
    train.random_init = random_init == "frustum" ? reconstruction::TrainOptions::RandomInit::kFrustum
                                                 : reconstruction::TrainOptions::RandomInit::kPhotoConsistent;
    train.mask_normalization =
        mask_normalization == "reference" ? reconstruction::MaskNormalization::kReference : reconstruction::MaskNormalization::kValid;
    train.large_prune = reconstruction::parse_large_prune(large_prune, "--large-prune");
    if (!background.empty()) {
      if (background.size() != 3) throw InputError("--background", "expected 3 values (R G B in [0, 1])");
      for (int c = 0; c < 3; ++c) train.background[c] = background[c];
    }
  }
};

}  // namespace weathergs::cli
