// Which weathergs made an output: the commit of the source tree, read when the build was configured,
// so that results and reports can name the code behind their numbers.
#pragma once

namespace weathergs {

// "abc1234" (git's short hash), "abc1234-dirty" when the tree had uncommitted changes at configure
// time, "unknown" outside a git checkout.
const char* source_commit();

}  // namespace weathergs
