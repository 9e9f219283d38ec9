// Refusals (core/scale/refusal.h): where the patches went, what the counts
// decide (the leading cause, a larger search bound and its size), and the
// linear stage's view rejections. Their words are tested with
// colmap/report/refusal_text (tests/colmap/report/refusal_text_test.cc).
#include <algorithm>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/blur/patch_grid.h"
#include "dpsfm/core/blur/patch_selection.h"
#include "dpsfm/core/scale/refusal.h"
#include "dpsfm/core/scale/view_patches.h"
#include "dpsfm/core/util/fields.h"
#include "tests/changed_fields.h"

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
            (Counts{{"blur beyond the search bound", 8},
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

// Hand-computed: 1.6 x 3 = 4.8 < 3 + 2 = 5 -> 5; 1.6 x 5 = 8 -> 8;
// 1.6 x 4.93 = 7.888 -> 8 (up to a half pixel); 1.6 x 8 = 12.8 -> 13.
TEST(LargerSearchBound, SixtyPercentOrTwoPixelsUpToAHalfPixel) {
  EXPECT_DOUBLE_EQ(LargerSearchBound(3), 5);
  EXPECT_DOUBLE_EQ(LargerSearchBound(5), 8);
  EXPECT_DOUBLE_EQ(LargerSearchBound(4.93), 8);
  EXPECT_DOUBLE_EQ(LargerSearchBound(8), 13);
  EXPECT_DOUBLE_EQ(LargerSearchBound(10.2), 16.5);  // 16.32 -> 16.5
}

TEST(SearchBoundReached, OnlyAnAutomaticBoundTheBlurReachesWhileGrowthsLast) {
  DPScaleOptions options;  // share 0.05, one growth
  EXPECT_TRUE(SearchBoundReached(100, 5, 0, options));    // exactly 5 %
  EXPECT_FALSE(SearchBoundReached(100, 4, 0, options));   // below
  EXPECT_FALSE(SearchBoundReached(0, 0, 0, options));     // nothing searched
  EXPECT_FALSE(SearchBoundReached(100, 50, 1, options));  // growth spent
  DPScaleOptions explicit_bound = options;
  explicit_bound.geometry.max_radius_px = 5;  // the user's bound stands
  EXPECT_FALSE(SearchBoundReached(100, 50, 0, explicit_bound));
}

// Twice the bound, up to a half pixel: 2 x 4.3 = 8.6 -> 9.
TEST(SearchBoundCap, TwiceTheBoundUpToAHalfPixel) {
  EXPECT_DOUBLE_EQ(SearchBoundCap(5), 10);
  EXPECT_DOUBLE_EQ(SearchBoundCap(4.3), 9);
  EXPECT_DOUBLE_EQ(SearchBoundCap(8.5), 17);
}

// Beyond-the-bound patches say the blur runs past the bound, not how far:
// the bound goes to its cap, 2 x 5 = 10 px, while the crops fit twice into
// the frame's short side, else to LargerSearchBound(5) = max(1.6 x 5, 7) =
// 8 px, else it stays. The 5 px geometry's patch is 2 x 5 + 21 = 31 px;
// the disk's kernels need a border of about the bound, so the crops are
// about 51 px at 10 px and 47 px at 8 px.
TEST(GrownSearchBound, ToTheCapWhileTheCropsFit) {
  const DPPsfField field =
      DPPsfField::Uniform(std::make_shared<TranslatingDiskPsf>());
  BlurEstimationOptions blur;
  const PatchGeometry g = PatchGeometryForRadius(5, 1);
  EXPECT_DOUBLE_EQ(GrownSearchBound(g, cv::Size(768, 512), field, blur), 10);
  const int crop_cap = g.patch_size + 2 * BlurSearchBorder(field, blur, 10);
  const int crop_larger = g.patch_size + 2 * BlurSearchBorder(field, blur, 8);
  ASSERT_LT(crop_larger, crop_cap);
  const int between = 2 * crop_larger + 1;  // the larger fits, the cap not
  EXPECT_DOUBLE_EQ(GrownSearchBound(g, cv::Size(between, between), field, blur),
                   8);
  EXPECT_EQ(
      GrownSearchBound(g, cv::Size(2 * crop_larger - 1, 600), field, blur), 0);
}

// By hand, bound 5 px (cap 10), share 0.05: of 100 searched, two standard
// errors above 5 % is 5 + 2 sqrt(0.05 x 0.95 / 100) x 100 = 9.36 patches
// beyond the bound.
TEST(EarlyGrownSearchBound, OnlyWhenTheShareSettlesIt) {
  const DPPsfField field =
      DPPsfField::Uniform(std::make_shared<TranslatingDiskPsf>());
  BlurEstimationOptions blur;
  const PatchGeometry g = PatchGeometryForRadius(5, 1);
  const cv::Size frame(768, 512);
  DPScaleOptions options;
  auto early = [&](int searched, int beyond, int growths) {
    return EarlyGrownSearchBound(
        searched, beyond, growths, g, frame, field, blur, options);
  };
  EXPECT_DOUBLE_EQ(early(100, 10, 0), 10);
  EXPECT_EQ(early(100, 9, 0), 0);   // within two standard errors
  EXPECT_EQ(early(100, 10, 1), 0);  // growth spent
  EXPECT_EQ(early(0, 0, 0), 0);     // nothing searched
  DPScaleOptions explicit_bound = options;
  explicit_bound.geometry.max_radius_px = 5;
  EXPECT_EQ(
      EarlyGrownSearchBound(100, 50, 0, g, frame, field, blur, explicit_bound),
      0);
  // No grown bound's crops fit twice into 60 px: the bound stays.
  EXPECT_EQ(EarlyGrownSearchBound(
                100, 50, 0, g, cv::Size(60, 60), field, blur, options),
            0);
}

// Every fourth chosen patch, counted among the chosen ones; none when
// fewer than 40 would be taken.
TEST(GrowthSample, EveryFourthChosenPatch) {
  ViewBlurSearch search;
  search.chosen.assign(400, 0);
  for (int k = 0; k < 400; k += 2) search.chosen[k] = 1;  // 200 chosen
  const std::vector<char> sample = GrowthSample(search);
  int taken = 0;
  for (int k = 0; k < 400; ++k) {
    EXPECT_EQ(sample[k], k % 8 == 0 ? 1 : 0) << k;
    taken += sample[k];
  }
  EXPECT_EQ(taken, 50);
  search.chosen.assign(159, 1);  // 40 taken
  const std::vector<char> forty = GrowthSample(search);
  EXPECT_EQ(std::count(forty.begin(), forty.end(), 1), 40);
  search.chosen.assign(156, 1);  // 39: too few
  const std::vector<char> none = GrowthSample(search);
  EXPECT_EQ(std::count(none.begin(), none.end(), 1), 0);
}

// The blur search's estimators are built once per geometry (crop, search
// options) and kept across views; a geometry beyond the last two used is
// dropped and built again when it comes back.
TEST(BlurSearchEstimators, BuiltOncePerGeometryTheLastTwoKept) {
  DPPsfField field;
  field.layout = DPPsfLayout::ColumnBands(2);
  field.cells = {std::make_shared<TranslatingDiskPsf>(),
                 std::make_shared<TranslatingDiskPsf>()};
  BlurSearchEstimators estimators(field);
  BlurEstimationOptions blur;
  blur.max_radius_px = 4;
  const int crop = 16 + 2 * BlurSearchBorder(field, blur, 4);
  const PatchBlurEstimator* first = (*estimators.For(blur, crop))[0].get();
  EXPECT_EQ(estimators.NumBuilt(), 2);  // one per cell
  EXPECT_EQ((*estimators.For(blur, crop))[0].get(), first);
  EXPECT_EQ(estimators.NumBuilt(), 2);
  BlurEstimationOptions grown = blur;
  grown.max_radius_px = 6.5;
  const auto larger = estimators.For(grown, crop + 6);
  ASSERT_EQ(larger->size(), 2u);
  EXPECT_EQ((*larger)[1]->PatchSize(), cv::Size(crop + 6, crop + 6));
  EXPECT_DOUBLE_EQ((*larger)[1]->Options().max_radius_px, 6.5);
  EXPECT_EQ(estimators.NumBuilt(), 4);
  EXPECT_EQ((*estimators.For(blur, crop))[0].get(), first);  // still kept
  EXPECT_EQ(estimators.NumBuilt(), 4);
  // A third geometry drops the least recently used (the grown one).
  estimators.For(grown, crop);
  EXPECT_EQ(estimators.NumBuilt(), 6);
  EXPECT_EQ((*estimators.For(blur, crop))[0].get(), first);
  EXPECT_EQ(estimators.NumBuilt(), 6);
  estimators.For(grown, crop + 6);
  EXPECT_EQ(estimators.NumBuilt(), 8);
}

// Estimators a caller holds stay usable after the cache drops them.
TEST(BlurSearchEstimators, HeldEstimatorsOutliveTheirEviction) {
  const DPPsfField field =
      DPPsfField::Uniform(std::make_shared<TranslatingDiskPsf>());
  BlurSearchEstimators estimators(field);
  BlurEstimationOptions blur;
  blur.max_radius_px = 4;
  const int crop = 16 + 2 * BlurSearchBorder(field, blur, 4);
  const auto held = estimators.For(blur, crop);
  for (int k = 1; k <= BlurSearchEstimators::kMaxGeometries; ++k) {
    estimators.For(blur, crop + 2 * k);
  }
  const int built = estimators.NumBuilt();
  EXPECT_NE((*estimators.For(blur, crop))[0].get(), (*held)[0].get());
  EXPECT_EQ(estimators.NumBuilt(), built + 1);  // dropped, so built again
  ASSERT_EQ(held->size(), 1u);
  EXPECT_EQ((*held)[0]->PatchSize(), cv::Size(crop, crop));
  cv::Mat left(crop, crop, CV_32FC1), right(crop, crop, CV_32FC1);
  cv::randu(left, 0, 1);
  cv::randu(right, 0, 1);
  EXPECT_NO_THROW((*held)[0]->Estimate(left, right));
}

// Every field of the search options is part of the key: each one changed
// alone builds new estimators (the tables and searches depend on them).
TEST(BlurSearchEstimators, EachSearchOptionIsPartOfTheKey) {
  const DPPsfField field =
      DPPsfField::Uniform(std::make_shared<TranslatingDiskPsf>());
  BlurSearchEstimators estimators(field);
  BlurEstimationOptions blur;
  blur.max_radius_px = 4;
  const int crop = 16 + 2 * BlurSearchBorder(field, blur, 8);
  estimators.For(blur, crop);
  ASSERT_EQ(estimators.NumBuilt(), 1);
  int expected = 1;
  test::ForEachFieldChanged(
      blur, [&](std::size_t i, const BlurEstimationOptions& changed) {
        estimators.For(changed, crop);
        EXPECT_EQ(estimators.NumBuilt(), ++expected) << "field " << i;
        estimators.For(blur, crop);  // still held: the last two are kept
        EXPECT_EQ(estimators.NumBuilt(), expected) << "field " << i;
      });
  EXPECT_EQ(expected,
            1 + static_cast<int>(FieldCount<BlurEstimationOptions>()));
  estimators.For(blur, crop + 2);
  EXPECT_EQ(estimators.NumBuilt(), expected + 1);  // the crop too
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
