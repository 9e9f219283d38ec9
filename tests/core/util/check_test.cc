// The two kinds of check (core/util/check.h): a precondition's failure is a
// CheckFailure carrying the user's words apart; an invariant's is an
// InternalError, which a catch of std::invalid_argument (how patches, views
// and the command take an input's problem) does not take.
#include "dpsfm/core/util/check.h"

#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace dpsfm {
namespace {

TEST(DPSFMCheck, AFailedPreconditionIsACheckFailureWithTheUsersWords) {
  const int views = 0;
  try {
    DPSFM_CHECK_GT(views, 0) << "no views with DP frames";
    FAIL() << "no throw";
  } catch (const CheckFailure& failure) {
    EXPECT_EQ(failure.message(), "no views with DP frames");
    const std::string what = failure.what();
    EXPECT_NE(what.find("(views) > (0)"), std::string::npos) << what;
    EXPECT_NE(what.find("check_test.cc:"), std::string::npos) << what;
  }
  // A check that holds throws nothing.
  EXPECT_NO_THROW(DPSFM_CHECK(views == 0) << "unused");
}

TEST(DPSFMInvariant, AFailedInvariantIsAnInternalErrorNotAnInputs) {
  const int rows = 3;
  bool taken_as_input = false, taken_as_bug = false;
  try {
    try {
      DPSFM_INVARIANT(rows == 4) << "rows of the spectrum it made";
    } catch (const std::invalid_argument&) {
      taken_as_input = true;
    }
  } catch (const InternalError& error) {
    taken_as_bug = true;
    const std::string what = error.what();
    EXPECT_NE(what.find("rows == 4 does not hold (") , std::string::npos)
        << what;
    EXPECT_NE(what.find("check_test.cc:"), std::string::npos) << what;
    EXPECT_NE(what.find("): rows of the spectrum it made"), std::string::npos)
        << what;
  }
  EXPECT_FALSE(taken_as_input);
  EXPECT_TRUE(taken_as_bug);
  EXPECT_NO_THROW(DPSFM_INVARIANT(rows == 3));
}

}  // namespace
}  // namespace dpsfm
