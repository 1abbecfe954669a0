// weathergs export-nerfbaselines: a scored run in NerfBaselines' results layout (evaluator/nerfbaselines.h).
#include <cstdio>

#include "apps/command.h"
#include "evaluator/nerfbaselines.h"

namespace weathergs::cli {
namespace {

int run_export(const evaluator::NerfBaselinesExportOptions& o) {
  const evaluator::NerfBaselinesExport e = evaluator::export_nerfbaselines(o);
  std::printf("wrote %s: %d views, NerfBaselines protocol \"%s\", metrics %s\n", o.out.c_str(), e.views,
              e.results["evaluation_protocol"].get<std::string>().c_str(), e.results["metrics"].dump().c_str());
  return kExitOk;
}

Command make_export(CLI::App& root) {
  auto o = std::make_shared<evaluator::NerfBaselinesExportOptions>();
  CLI::App* sub = root.add_subcommand(
      "export-nerfbaselines",
      "Write a scored run in NerfBaselines' evaluation layout (results.json with per-image metrics and sha256 of "
      "renders and ground truth, predictions/color, predictions/gt-color; docs/evaluator.md)");
  sub->add_option("--results", o->results, "The weathergs results.json to export")->required();
  sub->add_option("--renders", o->renders, "The renders it scored (e.g. RUN/renders/test)")->required();
  sub->add_option("--data", o->dataset, "The dataset it was scored against")->required();
  sub->add_option("--out", o->out, "The export folder")->required();
  sub->add_flag("--force", o->force, "Replace an existing export folder");
  return {sub, [o] { return run_export(*o); }};
}

}  // namespace
}  // namespace weathergs::cli

WGS_REGISTER_COMMAND(export_nerfbaselines, weathergs::cli::make_export)
