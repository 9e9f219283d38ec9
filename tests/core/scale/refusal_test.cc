// Refusals (core/scale/refusal.h): where the patches went, what the counts
// decide (the leading cause, a larger search bound and its size), and the
// linear stage's view rejections. Their words are tested with
// colmap/report/refusal_text (tests/colmap/report/refusal_text_test.cc).
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/blur/patch_selection.h"
#include "dpsfm/core/scale/refusal.h"

namespace dpsfm {
namespace test {
namespace {

using Counts = std::vector<std::pair<std::string, int>>;

TEST(PatchAccount, SumsViewsAndSizesTheLargerSearchBound) {
  ViewPatchCounts a{60, 20, {{kBlurAtSearchBound, 6}}, 6.5};
  ViewPatchCounts b{40, 10, {{kBlurAtSearchBound, 4}, {"no depth", 3}}, 5.0};
  const PatchAccount account = AccountPatches({a, b});
  EXPECT_EQ(account.tried, 100);
  EXPECT_EQ(account.usable, 30);
  EXPECT_EQ(account.at_search_bound, 10);
  EXPECT_DOUBLE_EQ(account.max_radius_px, 6.5);
  // 10 of 100 >= 5 %: a bound of ceil(max(1.6 x 6.5, 6.5 + 2)) = 11 px.
  EXPECT_TRUE(account.SearchBoundLimits());
  EXPECT_EQ(account.LargerSearchBound(), 11);
}

TEST(PatchAccount, FewPatchesAtTheBoundAskForNoLargerOne) {
  // 4 of 100 < 5 %.
  ViewPatchCounts a{100, 50, {{kBlurAtSearchBound, 4}}, 6.5};
  EXPECT_FALSE(AccountPatches({a}).SearchBoundLimits());
  // A small bound: ceil(max(1.6 x 3, 3 + 2)) = 5.
  ViewPatchCounts b{100, 50, {{kBlurAtSearchBound, 50}}, 3.0};
  EXPECT_TRUE(AccountPatches({b}).SearchBoundLimits());
  EXPECT_EQ(AccountPatches({b}).LargerSearchBound(), 5);
}

TEST(CountsToString, CountThenReasonInTheGivenOrder) {
  EXPECT_EQ(CountsToString({{"without depth", 3}, {"across a depth edge", 12}}),
            "3 without depth, 12 across a depth edge");
  EXPECT_EQ(CountsToString({}), "");
}

// Two views by hand: 100 patches tried, 8 usable; 55 with too little
// texture (>= half: the leading cause), 8 at the search bound (>= 5 %: a
// larger bound), 2 without depth; 10 left unsearched by design (not a
// rejection).
TEST(PatchAccount, LeadingCauseRejectionsAndBoundByHand) {
  const ViewPatchCounts a{
      60,
      5,
      {{kTextureTooWeak, 40}, {kLeftUnsearched, 10}, {"without depth", 2}},
      10.0};
  const ViewPatchCounts b{
      40, 3, {{kTextureTooWeak, 15}, {kBlurAtSearchBound, 8}}, 8.0};
  const PatchAccount account = AccountPatches({a, b});
  EXPECT_EQ(account.tried, 100);
  EXPECT_EQ(account.usable, 8);
  EXPECT_EQ(account.at_search_bound, 8);
  EXPECT_EQ(account.texture_too_weak, 55);
  EXPECT_DOUBLE_EQ(account.max_radius_px, 10.0);
  EXPECT_TRUE(account.TextureLeads());
  // Reasons summed over the views, in the order of their names, without the
  // unsearched ones.
  EXPECT_EQ(account.rejections,
            (Counts{{"blur at the search bound", 8},
                    {"with texture too weak for the noise", 55},
                    {"without depth", 2}}));
  // 8 of 100 >= 5 %; the larger bound ceil(max(1.6 x 10, 10 + 2)) = 16.
  EXPECT_TRUE(account.SearchBoundLimits());
  EXPECT_EQ(account.LargerSearchBound(), 16);
}

TEST(PatchAccount, ThresholdsAtTheirEdges) {
  // Texture: 50 of 100 is half (a leading cause), 49 is not.
  EXPECT_TRUE(
      AccountPatches({{100, 0, {{kTextureTooWeak, 50}}, 5.0}}).TextureLeads());
  EXPECT_FALSE(
      AccountPatches({{100, 0, {{kTextureTooWeak, 49}}, 5.0}}).TextureLeads());
  // The bound: 5 of 100 is 5 % (a larger one), with
  // ceil(max(1.6 x 12.75, 14.75)) = ceil(20.4) = 21.
  const PatchAccount at_edge =
      AccountPatches({{100, 0, {{kBlurAtSearchBound, 5}}, 12.75}});
  EXPECT_TRUE(at_edge.SearchBoundLimits());
  EXPECT_EQ(at_edge.LargerSearchBound(), 21);
  // A bound of unknown size (0) asks for none.
  EXPECT_FALSE(AccountPatches({{100, 0, {{kBlurAtSearchBound, 50}}, 0.0}})
                   .SearchBoundLimits());
  // No rejections: none listed, none leading; nothing tried, no bound.
  const PatchAccount clean = AccountPatches({{10, 10, {}, 5.0}});
  EXPECT_TRUE(clean.rejections.empty());
  EXPECT_FALSE(clean.TextureLeads());
  EXPECT_FALSE(AccountPatches({}).SearchBoundLimits());
  EXPECT_FALSE(AccountPatches({}).TextureLeads());
}

TEST(LinearFailure, SwappedViewsWhenMostViewsHaveANegativeScale) {
  LinearFailure failure;
  EXPECT_FALSE(failure.SwappedViewsLikely());
  failure.view_rejections = {{3, ViewRejection::kNonPositiveScale},
                             {1, ViewRejection::kSmallBlurRange}};
  EXPECT_TRUE(failure.SwappedViewsLikely());
  failure.view_rejections = {{3, ViewRejection::kSmallBlurRange},
                             {1, ViewRejection::kNonPositiveScale}};
  EXPECT_FALSE(failure.SwappedViewsLikely());
}

TEST(ScaleRefusalName, EveryCodeHasOne) {
  for (ScaleRefusal code : {ScaleRefusal::kNone,
                            ScaleRefusal::kNoViews,
                            ScaleRefusal::kLinearStageThrew,
                            ScaleRefusal::kTranslatingDiskRejected,
                            ScaleRefusal::kLinearStageFailed,
                            ScaleRefusal::kScaleOpen,
                            ScaleRefusal::kCuesNotCombined}) {
    EXPECT_NE(std::string(ScaleRefusalName(code)), "?");
    EXPECT_EQ(std::string(ScaleRefusalName(code)).find("--"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
