// What a command's run ended in: success, or the one line that says why not.
#pragma once

#include <string>

namespace dpsfm {

struct RunOutcome {
  bool success = false;
  std::string failure;
  static RunOutcome Success() { return {true, ""}; }
  static RunOutcome Failure(const std::string& why) { return {false, why}; }
};

}  // namespace dpsfm
