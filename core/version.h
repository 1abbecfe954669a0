// Which weathergs made an output: the commit of the source tree, read at every build
// (cmake/CommitStamp.cmake), so that results and reports can name the code behind their numbers.
#pragma once

namespace weathergs {

// "abc1234" (git's short hash), "abc1234-dirty" when tracked files differed from it at build time,
// "unknown" outside a git checkout.
const char* source_commit();

}  // namespace weathergs
