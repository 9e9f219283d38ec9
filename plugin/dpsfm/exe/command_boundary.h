// Where a command's run meets the shell: what the user must fix (InputError)
// and a failed outcome become one "ERROR: <command>: <why>" line on stderr
// and EXIT_FAILURE; so do running out of memory (said as such) and anything
// else thrown, which is a bug: "internal error", with the failed invariant's
// file and line (core/util/check.h), asking for a report.
#pragma once

#include <functional>
#include <string>

#include "dpsfm/colmap/controllers/run_outcome.h"

namespace dpsfm {

int RunAtCommandBoundary(const std::string& command,
                         const std::function<RunOutcome()>& run);

}  // namespace dpsfm
