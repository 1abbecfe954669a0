// The radiance-field backend: nerf/'s training run, which keeps its snapshots' renders itself.
#include "methods/backend.h"

namespace weathergs::methods {

namespace {

class FieldBackend final : public Backend {
 public:
  FieldBackend(BackendRun run, const nerf::NerfOptions& nerf, int checkpoint_every)
      : run_(std::move(run)), nerf_(nerf), checkpoint_every_(checkpoint_every) {}

  int iterations() const override { return nerf_.iterations; }

  std::vector<int> snapshots() const override { return scored_snapshots(run_.snapshots, iterations()); }

  StageOutput model_output() const override {
    return nerf::nerf_run_output(run_.model_dir, run_.dataset, run_.inputs, nerf_);
  }

  TrainOutcome train(const reconstruction::IterationCallback& on_iteration) override {
    nerf::NerfRunOptions t;
    t.dataset = run_.dataset;
    t.inputs = run_.inputs;
    t.out = run_.model_dir;
    t.method = run_.method;
    t.nerf = nerf_;
    t.snapshot_at = snapshot_iterations(run_.snapshots, iterations());
    t.checkpoint_every = checkpoint_every_;
    t.resume = model_output().state == StageOutput::State::kPartial;
    t.force = !t.resume;  // leftovers of a run that cannot resume are replaced
    const nerf::NerfRunResult r = nerf::train_nerf_run(t, [&](const nerf::NerfIterationStats& st) {
      if (!on_iteration) return;
      reconstruction::IterationStats is;
      is.iteration = st.iteration;
      is.loss = st.loss;
      is.psnr = st.psnr;
      on_iteration(is);
    });
    return {t.resume, r.peak_rss_mb};
  }

  RenderOutcome render(const std::string& split, const std::string& out) override {
    nerf::NerfRenderOptions r;
    r.model = run_.model_dir;
    r.dataset = run_.dataset;
    r.split = split;
    r.method = run_.method;
    r.out = out;
    const nerf::NerfRenderResult res = nerf::render_nerf_run(r);
    return {res.views, res.render_seconds};
  }

  std::string snapshot_renders(int iteration, const std::string&) override {
    return nerf::nerf_snapshot_dir(run_.model_dir, iteration);
  }

 private:
  BackendRun run_;
  nerf::NerfOptions nerf_;
  int checkpoint_every_;
};

}  // namespace

std::unique_ptr<Backend> make_nerf_backend(BackendRun run, const nerf::NerfOptions& nerf, int checkpoint_every) {
  return std::make_unique<FieldBackend>(std::move(run), nerf, checkpoint_every);
}

}  // namespace weathergs::methods
