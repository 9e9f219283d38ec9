#include "dpsfm/core/util/check.h"

namespace dpsfm {
namespace {

std::string& Failure() {
  thread_local std::string failure;
  return failure;
}

}  // namespace

const std::string& OptionCheckFailure() { return Failure(); }

namespace internal {

void SetOptionCheckFailure(const std::string& failure) { Failure() = failure; }

void PrefixOptionCheckFailure(const char* field) {
  Failure() = std::string(field) + "." + Failure();
}

void ThrowInvalidOptions(const char* name) {
  throw std::invalid_argument(std::string("invalid ") + name + ": " +
                              Failure());
}

}  // namespace internal
}  // namespace dpsfm
