// Refusal wording (core/scale/refusal.h): where the patches went, and the
// option a refusal names when many patches hit the blur search's bound.
#include <string>

#include <gtest/gtest.h>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/blur/patch_selection.h"
#include "dpsfm/core/scale/refusal.h"

namespace dpsfm {
namespace test {
namespace {

TEST(PatchAccount, SumsViewsAndNamesTheLargerSearchBound) {
  ViewPatchCounts a{60, 20, {{kBlurAtSearchBound, 6}}, 6.5};
  ViewPatchCounts b{40, 10, {{kBlurAtSearchBound, 4}, {"no depth", 3}}, 5.0};
  const PatchAccount account = AccountPatches({a, b});
  EXPECT_EQ(account.tried, 100);
  EXPECT_EQ(account.usable, 30);
  EXPECT_EQ(account.at_search_bound, 10);
  EXPECT_DOUBLE_EQ(account.max_radius_px, 6.5);
  // 10 of 100 >= 5 %: a bound of ceil(max(1.6 x 6.5, 6.5 + 2)) = 11 px.
  const std::string fixes = account.Fixes();
  EXPECT_NE(fixes.find("10 of 100 patches"), std::string::npos) << fixes;
  EXPECT_NE(fixes.find("--DPScaleEstimator.max_radius_px 11"),
            std::string::npos)
      << fixes;
}

TEST(PatchAccount, FewPatchesAtTheBoundNameNothing) {
  // 4 of 100 < 5 %.
  ViewPatchCounts a{100, 50, {{kBlurAtSearchBound, 4}}, 6.5};
  EXPECT_EQ(AccountPatches({a}).Fixes(), "");
  // A small bound: ceil(max(1.6 x 3, 3 + 2)) = 5.
  ViewPatchCounts b{100, 50, {{kBlurAtSearchBound, 50}}, 3.0};
  EXPECT_NE(AccountPatches({b}).Fixes().find("max_radius_px 5"),
            std::string::npos);
}

TEST(CalibratedProfileOpenReason, AdvisesRecordingTheFocusOnlyWithoutOne) {
  const std::string without =
      CalibratedProfileOpenReason(0.22, 0.39, 0.28, 3.39, 0.3, false);
  EXPECT_NE(without.find("Record the focus distance"), std::string::npos);
  EXPECT_NE(without.find("between 0.2800 and 3.3900"), std::string::npos)
      << without;
  const std::string with =
      CalibratedProfileOpenReason(0.22, 0.39, 0.28, 3.39, 0.3, true);
  EXPECT_EQ(with.find("Record the focus distance"), std::string::npos) << with;
  EXPECT_NE(with.find("recorded_focus_tolerance"), std::string::npos);
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
