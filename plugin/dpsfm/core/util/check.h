// Validation for the core. The core never aborts the process. Two kinds of
// check, told apart by what a failure means:
// - DPSFM_CHECK: a precondition the caller's data can violate (a view too
//   small, lens data out of range). It throws CheckFailure (a
//   std::invalid_argument) with a readable message; a patch, a view or the
//   command reports it as that input's problem (COLMAP's THROW_CHECK style,
//   without depending on COLMAP).
// - DPSFM_INVARIANT: what the code guarantees itself (buffers it made, sizes
//   it chose). It throws InternalError, which nothing turns into an input's
//   problem: the command reports it as a bug, with the file and line.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace dpsfm {

// What a failed DPSFM_CHECK throws: what() has the condition and the source
// line (for developers and logs); message() only the text streamed after
// it, in words for a user ("" when none was given), which the command
// boundary shows with the input it concerns.
class CheckFailure : public std::invalid_argument {
 public:
  CheckFailure(const std::string& what, std::string message)
      : std::invalid_argument(what), message_(std::move(message)) {}
  const std::string& message() const { return message_; }

 private:
  std::string message_;
};

// What a failed DPSFM_INVARIANT throws: a bug, not the input's fault.
// what() has the condition, the source line and the message.
class InternalError : public std::logic_error {
 public:
  explicit InternalError(const std::string& what) : std::logic_error(what) {}
};

namespace internal {

class InvariantMessage {
 public:
  InvariantMessage(const char* file, int line, const char* condition) {
    stream_ << condition << " does not hold (" << file << ":" << line << ")";
  }
  ~InvariantMessage() noexcept(false) { throw InternalError(stream_.str()); }
  template <typename T>
  InvariantMessage& operator<<(const T& value) {
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

class CheckMessage {
 public:
  CheckMessage(const char* file, int line, const char* condition) {
    stream_ << "Check failed: " << condition << " (" << file << ":" << line
            << ")";
  }
  ~CheckMessage() noexcept(false) {
    throw CheckFailure(stream_.str(), message_.str());
  }
  template <typename T>
  CheckMessage& operator<<(const T& value) {
    if (first_) {
      stream_ << ": ";
      first_ = false;
    }
    stream_ << value;
    message_ << value;
    return *this;
  }

 private:
  std::ostringstream stream_;
  std::ostringstream message_;
  bool first_ = true;
};

}  // namespace internal
}  // namespace dpsfm

// DPSFM_CHECK(x > 0) << "x must be positive, got " << x;
#define DPSFM_CHECK(condition) \
  if (condition) {             \
  } else                       \
    ::dpsfm::internal::CheckMessage(__FILE__, __LINE__, #condition)

// DPSFM_INVARIANT(spectrum.isContinuous()) << "the spectrum it allocated";
#define DPSFM_INVARIANT(condition) \
  if (condition) {                 \
  } else                           \
    ::dpsfm::internal::InvariantMessage(__FILE__, __LINE__, #condition)

#define DPSFM_CHECK_GT(a, b) DPSFM_CHECK((a) > (b))
#define DPSFM_CHECK_GE(a, b) DPSFM_CHECK((a) >= (b))
#define DPSFM_CHECK_LT(a, b) DPSFM_CHECK((a) < (b))
#define DPSFM_CHECK_LE(a, b) DPSFM_CHECK((a) <= (b))
#define DPSFM_CHECK_EQ(a, b) DPSFM_CHECK((a) == (b))

// Option structs (COLMAP's CHECK_OPTION_* style): every struct of options
// has `bool Check(std::string* failure = nullptr) const` made of these; the
// first failed check returns false and, when the caller passed `failure`,
// writes there the field, the bound and the value given, e.g. "min_views >= 1
// (got 0)". Nothing is kept anywhere else: the failure is returned to the
// caller that asked. The macros name the parameter `failure`.
// DPSFM_CHECK_OPTIONS acts on a Check() by throwing
// std::invalid_argument("invalid <Name>: <failure>").
//
//   bool ViewBudgetOptions::Check(std::string* failure) const {
//     DPSFM_CHECK_OPTION_GE(min_views, 1);
//     DPSFM_CHECK_OPTION_VALUE(settled_change > 0 && settled_change < 1,
//                              settled_change);
//     DPSFM_CHECK_NESTED_OPTIONS(blur);  // "blur.max_radius_px >= 1 (...)"
//     return true;
//   }
//   DPSFM_CHECK_OPTIONS(options, "ViewBudgetOptions");
namespace dpsfm {

// What `options.Check()` finds wrong ("" if nothing).
template <typename Options>
std::string OptionCheckFailure(const Options& options) {
  std::string failure;
  options.Check(&failure);
  return failure;
}

namespace internal {

// False, with `text` written to *failure when the caller asked for it.
inline bool FailOptionCheck(std::string* failure, const std::string& text) {
  if (failure != nullptr) *failure = text;
  return false;
}

[[noreturn]] void ThrowInvalidOptions(const char* name,
                                      const std::string& failure);

template <typename T>
bool CheckOptionValue(bool ok,
                      const char* condition,
                      const T& value,
                      std::string* failure) {
  if (!ok && failure != nullptr) {
    std::ostringstream text;
    text << condition << " (got " << value << ")";
    *failure = text.str();
  }
  return ok;
}

}  // namespace internal
}  // namespace dpsfm

#define DPSFM_CHECK_OPTION_VALUE(condition, value)      \
  if (!::dpsfm::internal::CheckOptionValue(             \
          (condition), #condition, (value), failure)) { \
    return false;                                       \
  }
// With the message a user should read instead of the condition.
#define DPSFM_CHECK_OPTION_MESSAGE(condition, message)             \
  if (!(condition)) {                                              \
    return ::dpsfm::internal::FailOptionCheck(failure, (message)); \
  }
#define DPSFM_CHECK_OPTION_OP(a, op, b)                 \
  if (!::dpsfm::internal::CheckOptionValue(             \
          (a)op(b), #a " " #op " " #b, (a), failure)) { \
    return false;                                       \
  }
#define DPSFM_CHECK_OPTION_GT(a, b) DPSFM_CHECK_OPTION_OP(a, >, b)
#define DPSFM_CHECK_OPTION_GE(a, b) DPSFM_CHECK_OPTION_OP(a, >=, b)
#define DPSFM_CHECK_OPTION_LT(a, b) DPSFM_CHECK_OPTION_OP(a, <, b)
#define DPSFM_CHECK_OPTION_LE(a, b) DPSFM_CHECK_OPTION_OP(a, <=, b)
// A nested options struct: its failure, prefixed with the field's name.
#define DPSFM_CHECK_NESTED_OPTIONS(field)                       \
  {                                                             \
    std::string nested_failure;                                 \
    if (!(field).Check(&nested_failure)) {                      \
      return ::dpsfm::internal::FailOptionCheck(                \
          failure, std::string(#field) + "." + nested_failure); \
    }                                                           \
  }
// Acting on a Check(): throws std::invalid_argument naming the struct.
#define DPSFM_CHECK_OPTIONS(options, name)                             \
  {                                                                    \
    std::string options_failure;                                       \
    if (!(options).Check(&options_failure)) {                          \
      ::dpsfm::internal::ThrowInvalidOptions((name), options_failure); \
    }                                                                  \
  }
