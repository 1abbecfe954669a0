// weathergs render: render a trained 3DGS run for the evaluator (one PNG per view + info.json).
#include <cstdio>

#include "apps/command.h"
#include "core/progress.h"
#include "reconstruction/run.h"

namespace weathergs::cli {
namespace {

int run_render(const reconstruction::RenderRunOptions& o) {
  const reconstruction::RenderRunResult r = reconstruction::render_run(o);
  if (!is_quiet())
    std::fprintf(stderr, "rendered %d views of split '%s' in %.2f s into %s\n", r.views, o.split.c_str(),
                 r.render_seconds, o.out.c_str());
  return kExitOk;
}

Command make_render(CLI::App& root) {
  auto o = std::make_shared<reconstruction::RenderRunOptions>();
  CLI::App* sub = root.add_subcommand("render", "Render a trained 3DGS run (PNG per view + info.json)");
  sub->add_option("--model", o->model, "Run folder written by `weathergs train`")->required();
  sub->add_option("--split", o->split, "Dataset split to render (or all: every view)")->capture_default_str();
  sub->add_flag("--depth", o->depth,
                "Also write planar depth EXRs to <out>/depth/<view>.exr (the dataset convention), e.g. to weather "
                "an imported capture (docs/scenes.md)");
  sub->add_option("--depth-min-opacity", o->depth_min_opacity,
                  "Accumulated opacity below which a depth pixel is background (+inf)")
      ->capture_default_str();
  sub->add_option("--data", o->dataset, "Dataset folder (default: the one the run was trained on)");
  sub->add_option("--method", o->method, "Method name recorded in info.json")->capture_default_str();
  sub->add_option("--out", o->out, "Output folder (replaced atomically)")->required();
  return {sub, [o] { return run_render(*o); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(render, weathergs::cli::make_render)
