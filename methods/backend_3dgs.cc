// The 3DGS backend: reconstruction/'s training run, its checkpoints and its renders.
#include <filesystem>

#include "methods/backend.h"

namespace weathergs::methods {

namespace {

namespace fs = std::filesystem;

class GaussianBackend final : public Backend {
 public:
  GaussianBackend(BackendRun run, const reconstruction::TrainOptions& train, int checkpoint_every)
      : run_(std::move(run)), train_(train), checkpoint_every_(checkpoint_every) {}

  int iterations() const override { return train_.iterations; }

  std::vector<int> snapshots() const override { return scored_snapshots(run_.snapshots, iterations()); }

  StageOutput model_output() const override { return reconstruction::run_output(run_.model_dir, train_); }

  TrainOutcome train(const reconstruction::IterationCallback& on_iteration) override {
    reconstruction::TrainRunOptions t;
    t.dataset = run_.dataset;
    t.inputs = run_.inputs;
    t.out = run_.model_dir;
    t.checkpoint_every = checkpoint_every_;
    t.snapshot_at = snapshot_iterations(run_.snapshots, iterations());
    t.train = train_;
    t.resume = model_output().state == StageOutput::State::kPartial;
    t.force = !t.resume;  // leftovers of a run that cannot resume are replaced
    const reconstruction::TrainRunResult r = reconstruction::train_run(t, on_iteration);
    return {t.resume, r.peak_rss_mb};
  }

  RenderOutcome render(const std::string& split, const std::string& out) override {
    const reconstruction::RenderRunResult r = reconstruction::render_run(render_options(split, out, 0));
    return {r.views, r.render_seconds};
  }

  std::string snapshot_renders(int iteration, const std::string& scratch) override {
    reconstruction::render_run(render_options("test", scratch, iteration));
    return scratch;
  }

 private:
  reconstruction::RenderRunOptions render_options(const std::string& split, const std::string& out, int snapshot) const {
    reconstruction::RenderRunOptions r;
    r.model = run_.model_dir;
    r.dataset = run_.dataset;
    r.split = split;
    r.method = run_.method;
    r.snapshot = snapshot;
    r.out = out;
    return r;
  }

  BackendRun run_;
  reconstruction::TrainOptions train_;
  int checkpoint_every_;
};

}  // namespace

std::unique_ptr<Backend> make_3dgs_backend(BackendRun run, const reconstruction::TrainOptions& train, int checkpoint_every) {
  return std::make_unique<GaussianBackend>(std::move(run), train, checkpoint_every);
}

}  // namespace weathergs::methods
