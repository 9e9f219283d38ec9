// Validation for the core. The core never aborts the process: a violated
// precondition throws std::invalid_argument with a readable message, which the
// command turns into one error line and a non-zero exit (COLMAP's THROW_CHECK
// style, without depending on COLMAP).
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace dpsfm {
namespace internal {

class CheckMessage {
 public:
  CheckMessage(const char* file, int line, const char* condition) {
    stream_ << "Check failed: " << condition << " (" << file << ":" << line
            << ")";
  }
  ~CheckMessage() noexcept(false) {
    throw std::invalid_argument(stream_.str());
  }
  template <typename T>
  CheckMessage& operator<<(const T& value) {
    if (first_) {
      stream_ << ": ";
      first_ = false;
    }
    stream_ << value;
    return *this;
  }

 private:
  std::ostringstream stream_;
  bool first_ = true;
};

}  // namespace internal
}  // namespace dpsfm

// DPSFM_CHECK(x > 0) << "x must be positive, got " << x;
#define DPSFM_CHECK(condition) \
  if (condition) {             \
  } else                       \
    ::dpsfm::internal::CheckMessage(__FILE__, __LINE__, #condition)

#define DPSFM_CHECK_GT(a, b) DPSFM_CHECK((a) > (b))
#define DPSFM_CHECK_GE(a, b) DPSFM_CHECK((a) >= (b))
#define DPSFM_CHECK_LT(a, b) DPSFM_CHECK((a) < (b))
#define DPSFM_CHECK_LE(a, b) DPSFM_CHECK((a) <= (b))
#define DPSFM_CHECK_EQ(a, b) DPSFM_CHECK((a) == (b))
