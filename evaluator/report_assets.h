// The results browser's page (evaluator/report_page/: index.html, report.css, report.js), embedded
// into the binary at build time (evaluator/CMakeLists.txt), so a report needs no installed files.
#pragma once

#include <string>
#include <vector>

namespace weathergs::evaluator {

struct ReportAsset {
  const char* name;      // file name in the report folder
  std::string contents;  // written verbatim
};

const std::vector<ReportAsset>& report_assets();

}  // namespace weathergs::evaluator
