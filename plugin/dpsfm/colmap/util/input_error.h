// The COLMAP layer's one error type for what the user must fix.
#pragma once

#include <stdexcept>
#include <string>

namespace dpsfm {

// A problem with the user's input (paths, workspace contents, option values).
// The command prints its message as one line and exits non-zero.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message)
      : std::runtime_error(message) {}
};

}  // namespace dpsfm
