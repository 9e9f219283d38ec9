// Where a command's run meets the shell: what the user must fix (InputError)
// and a failed outcome become one "ERROR: <command>: <why>" line on stderr
// and EXIT_FAILURE; anything else thrown is an internal error, said the
// same way.
#pragma once

#include <functional>
#include <string>

#include "dpsfm/colmap/controllers/run_outcome.h"

namespace dpsfm {

int RunAtCommandBoundary(const std::string& command,
                         const std::function<RunOutcome()>& run);

}  // namespace dpsfm
