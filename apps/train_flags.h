// The 3DGS trainer's flags that `train` and `reconstruct` share, defined once so that both read,
// default and document them the same way. Flags only `train` has (its inputs, --resume) stay there.
#pragma once

#include <CLI/CLI.hpp>
#include <algorithm>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/json_reader.h"
#include "reconstruction/trainer.h"

namespace weathergs::cli {

struct TrainFlags {
  using TrainOptions = reconstruction::TrainOptions;
  std::string random_init = "photo", mask_normalization = "valid", large_prune = "distance", schedule = "fast";
  std::vector<double> background;
  std::string options_file;

  // Binds the numeric flags to `train` and `checkpoint_every`; the named choices go through apply().
  void add_to(CLI::App* app, TrainOptions& train, int& checkpoint_every) {
    app_ = app;
    app->add_option("--train-options", options_file,
                    "TrainOptions as JSON, the keys of run.json's \"options\" (docs/reconstruction.md): a key it "
                    "leaves out keeps its default, and flags given on the command line override it")
        ->check(CLI::ExistingFile);
    field(app, "--iterations", &TrainOptions::iterations, train,
          "3DGS training iterations (default: the schedule's length; fast: 500 passes over the training views "
          "within 3000..30000, reference: 30000)")
        ->check(CLI::PositiveNumber);
    given(app->add_option("--schedule", schedule,
                          "fast (a length from the training views, a Gaussian budget of 2 per pixel), reference "
                          "(the protocol's 30,000-iteration schedule, scaled to a shorter --iterations) or unscaled "
                          "(every count as given); docs/schedules.md")
              ->capture_default_str()->check(CLI::IsMember({"fast", "reference", "unscaled"})),
          &TrainOptions::schedule);
    field(app, "--downsample-start", &TrainOptions::downsample_start, train,
          "Resolution schedule: train first on images box-downsampled by this factor (1, 2, 4, 8 or 16), halving "
          "at equal steps to full resolution at --full-resolution-at of the run, the Gaussian budget divided by "
          "the factor squared (1: full resolution throughout; at 4, 2.3x faster and 0.8 dB worse on a held-out scene: "
          "docs/schedules.md)")
        ->capture_default_str()->check(CLI::IsMember({1, 2, 4, 8, 16}));
    field(app, "--full-resolution-at", &TrainOptions::full_resolution_at, train,
          "Resolution schedule: the fraction of the run, in (0, 1], from which training uses full-resolution images")
        ->capture_default_str()->check(CLI::Range(0.0, 1.0));
    field(app, "--seed", &TrainOptions::seed, train,
          "Random seed (view order, random initialization; reconstruct: the radiance field's too)")
        ->capture_default_str();
    given(app->add_option("--background", background, "Background colour R G B in [0, 1] (default 0 0 0)")->expected(3),
          &TrainOptions::background);
    field(app, "--max-gaussians", &TrainOptions::max_gaussians, train,
          "Memory guard: densification never grows the model beyond this many Gaussians (~2.6 KiB each; "
          "the fast schedule's budget, 2 per pixel of a training image, caps the default)")
        ->capture_default_str();
    given(app->add_option("--random-init", random_init,
                          "Random initialization when there are no SfM points: photo (each point at the depth where "
                          "neighbouring views agree) or frustum (uniform in inverse depth, random colours)")
              ->capture_default_str()->check(CLI::IsMember({"photo", "frustum"})),
          &TrainOptions::random_init);
    field(app, "--random-init-count", &TrainOptions::random_init_count, train,
          "Gaussians of the random initialization (used when there are no SfM points)")
        ->capture_default_str();
    given(app->add_option("--mask-normalization", mask_normalization,
                          "Masked loss: valid (means over the valid pixels, masked ones count for nothing) or reference "
                          "(the WeatherGS release: masked target pixels replaced by the render, means over all pixels); "
                          "docs/reconstruction.md")
              ->capture_default_str()->check(CLI::IsMember({"valid", "reference"})),
          &TrainOptions::mask_normalization);
    given(app->add_option("--large-prune", large_prune,
                          "Large-Gaussian prune (from --large-prune-from on): distance (a Gaussian may be up to "
                          "max_world_size x the larger of the cameras' extent and its distance from the rig) or "
                          "camera_extent (the reference: max_world_size x the cameras' extent; collapses forward-facing "
                          "scenes at 30,000 iterations); docs/reconstruction.md")
              ->capture_default_str()->check(CLI::IsMember({"distance", "camera_extent"})),
          &TrainOptions::large_prune);
    field(app, "--large-prune-from", &TrainOptions::large_prune_from, train,
          "Iteration after which the large-Gaussian prune runs (at densification steps); the default, "
          "the reference's first opacity reset, is scaled with --iterations like the densification window")
        ->capture_default_str()->check(CLI::NonNegativeNumber);
    field(app, "--distractor-opacity-weight", &TrainOptions::distractor_opacity_weight, train,
          "desplat: opacity penalty of the per-view distractor Gaussians: the loss gains this x the image "
          "fraction their opacity covers (docs/reconstruction.md)")
        ->capture_default_str()->check(CLI::NonNegativeNumber);
    app->add_option("--checkpoint-every", checkpoint_every, "Iterations between checkpoints (0 = only at the end)")
        ->capture_default_str()->check(CLI::NonNegativeNumber);
  }

  // After parsing: the options file under the flags given, then the named choices and the background.
  void apply(TrainOptions& train) {
    TrainOptions parsed = train;
    parsed.random_init = random_init == "frustum" ? TrainOptions::RandomInit::kFrustum : TrainOptions::RandomInit::kPhotoConsistent;
    parsed.mask_normalization =
        mask_normalization == "reference" ? reconstruction::MaskNormalization::kReference : reconstruction::MaskNormalization::kValid;
    parsed.large_prune = reconstruction::parse_large_prune(large_prune, "--large-prune");
    parsed.schedule = reconstruction::parse_schedule(schedule, "--schedule");
    if (!background.empty()) {
      if (background.size() != 3) throw InputError("--background", "expected 3 values (R G B in [0, 1])");
      for (int c = 0; c < 3; ++c) parsed.background[c] = background[c];
    }
    if (options_file.empty()) {
      train = parsed;
      return;
    }
    const JsonReader file = JsonReader::from_file(options_file);
    train = TrainOptions::from_user_json(file);
    file_keys_.clear();
    for (const auto& [key, value] : file.value().items()) file_keys_.push_back(key);
    for (const auto& [option, copy] : copies_)
      if (option->count() > 0) copy(parsed, train);
  }

  // Whether the user set TrainOptions' `key`: its flag (--key with '-' for '_') given on the command
  // line, or the --train-options file holding it. What reconstruction/unread_settings.h judges.
  bool is_set(const std::string& key) const { return flag_given(key) || has_file_key(key); }
  // Where the user set `key`, for a message: the flag, else "FILE:/key".
  std::string where(const std::string& key) const { return flag_given(key) ? flag_of(key) : options_file + ":/" + key; }
  bool has_file_key(const std::string& key) const {
    return std::find(file_keys_.begin(), file_keys_.end(), key) != file_keys_.end();
  }

 private:
  CLI::App* app_ = nullptr;
  std::vector<std::string> file_keys_;  // the keys of the --train-options file

  static std::string flag_of(const std::string& key) {
    std::string flag = "--" + key;
    std::replace(flag.begin(), flag.end(), '_', '-');
    return flag;
  }
  bool flag_given(const std::string& key) const {
    const CLI::Option* o = app_ ? app_->get_option_no_throw(flag_of(key)) : nullptr;
    return o && o->count() > 0;
  }
  // Each flag that sets a TrainOptions field, with the copy of that field a given flag makes.
  std::vector<std::pair<CLI::Option*, std::function<void(const TrainOptions&, TrainOptions&)>>> copies_;

  template <typename T>
  CLI::Option* given(CLI::Option* option, T TrainOptions::*member) {
    copies_.push_back({option, [member](const TrainOptions& from, TrainOptions& to) { to.*member = from.*member; }});
    return option;
  }
  template <typename T>
  CLI::Option* field(CLI::App* app, const char* name, T TrainOptions::*member, TrainOptions& train, const char* help) {
    return given(app->add_option(name, train.*member, help), member);
  }
};

}  // namespace weathergs::cli
