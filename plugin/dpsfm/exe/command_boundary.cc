#include "dpsfm/exe/command_boundary.h"

#include <cstdlib>
#include <exception>
#include <iostream>
#include <new>

#include "dpsfm/colmap/util/input_error.h"
#include "dpsfm/core/util/check.h"

namespace dpsfm {
namespace {

int Fail(const std::string& command, const std::string& message) {
  std::cerr << "ERROR: " << command << ": " << message << std::endl;
  return EXIT_FAILURE;
}

}  // namespace

int RunAtCommandBoundary(const std::string& command,
                         const std::function<RunOutcome()>& run) {
  try {
    const RunOutcome outcome = run();
    if (!outcome.success) return Fail(command, outcome.failure);
    return EXIT_SUCCESS;
  } catch (const InputError& error) {
    return Fail(command, error.what());
  } catch (const std::bad_alloc&) {
    return Fail(command,
                "out of memory; nothing was changed (fewer threads, the "
                "command's num_threads option, need less)");
  } catch (const std::exception& error) {
    // An invariant (InternalError, with its file and line), or anything a
    // library threw that the run did not expect: a bug, not the input's.
    return Fail(command,
                std::string("internal error (a bug in dp-sfm; please report "
                            "it with this line and the log): ") +
                    error.what());
  }
}

}  // namespace dpsfm
