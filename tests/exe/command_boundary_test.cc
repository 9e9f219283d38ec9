// The command boundary words each kind of failure for a user: the input's
// problem as it is, running out of memory as such, and a failed invariant
// or an unexpected library exception as a bug with its file and line.
#include "dpsfm/exe/command_boundary.h"

#include <cstdlib>
#include <new>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "dpsfm/colmap/util/input_error.h"
#include "dpsfm/core/util/check.h"

namespace dpsfm {
namespace {

// The exit status and what was printed on stderr.
struct Boundary {
  int status = 0;
  std::string printed;
};

Boundary RunCommand(const std::function<RunOutcome()>& run) {
  Boundary b;
  testing::internal::CaptureStderr();
  b.status = RunAtCommandBoundary("dp_test", run);
  b.printed = testing::internal::GetCapturedStderr();
  return b;
}

TEST(RunAtCommandBoundary, SuccessIsSilent) {
  const Boundary b = RunCommand([] { return RunOutcome::Success(); });
  EXPECT_EQ(b.status, EXIT_SUCCESS);
  EXPECT_EQ(b.printed, "");
}

TEST(RunAtCommandBoundary, AnInputErrorIsOneLineInItsOwnWords) {
  const Boundary b = RunCommand([]() -> RunOutcome {
    throw InputError("image a.png: no DP views");
  });
  EXPECT_EQ(b.status, EXIT_FAILURE);
  EXPECT_EQ(b.printed, "ERROR: dp_test: image a.png: no DP views\n");
}

TEST(RunAtCommandBoundary, AFailedInvariantIsABugWithItsFileAndLine) {
  const Boundary b = RunCommand([]() -> RunOutcome {
    const int rows = 3;
    DPSFM_INVARIANT(rows == 4) << "the spectrum it allocated";
    return RunOutcome();
  });
  EXPECT_EQ(b.status, EXIT_FAILURE);
  EXPECT_EQ(b.printed.rfind("ERROR: dp_test: internal error (a bug in dp-sfm; "
                            "please report it",
                            0),
            0u)
      << b.printed;
  EXPECT_NE(b.printed.find("rows == 4 does not hold"), std::string::npos)
      << b.printed;
  EXPECT_NE(b.printed.find("command_boundary_test.cc:"), std::string::npos)
      << b.printed;
  EXPECT_NE(b.printed.find("the spectrum it allocated"), std::string::npos)
      << b.printed;
  EXPECT_EQ(b.printed.find('\n'), b.printed.size() - 1) << "one line";
}

TEST(RunAtCommandBoundary, NoMemoryIsSaidAsSuch) {
  const Boundary b =
      RunCommand([]() -> RunOutcome { throw std::bad_alloc(); });
  EXPECT_EQ(b.status, EXIT_FAILURE);
  EXPECT_NE(b.printed.find("out of memory; nothing was changed"),
            std::string::npos)
      << b.printed;
  EXPECT_EQ(b.printed.find("internal error"), std::string::npos) << b.printed;
}

TEST(RunAtCommandBoundary, AFailedOutcomeIsItsReason) {
  const Boundary b = RunCommand([] {
    return RunOutcome::Failure("the interval is 56 % wide (limit 30 %)");
  });
  EXPECT_EQ(b.status, EXIT_FAILURE);
  EXPECT_EQ(b.printed,
            "ERROR: dp_test: the interval is 56 % wide (limit 30 %)\n");
}

}  // namespace
}  // namespace dpsfm
