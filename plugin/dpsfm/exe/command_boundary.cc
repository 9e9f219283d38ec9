#include "dpsfm/exe/command_boundary.h"

#include <cstdlib>
#include <exception>
#include <iostream>

#include "dpsfm/colmap/util/input_error.h"

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
  } catch (const std::exception& error) {
    return Fail(command, std::string("internal error: ") + error.what());
  }
}

}  // namespace dpsfm
