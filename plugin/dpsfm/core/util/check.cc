#include "dpsfm/core/util/check.h"

namespace dpsfm {
namespace internal {

void ThrowInvalidOptions(const char* name, const std::string& failure) {
  throw std::invalid_argument(std::string("invalid ") + name + ": " + failure);
}

}  // namespace internal
}  // namespace dpsfm
