// Refusal wording (core/scale/refusal.h): where the patches went, and the
// option a refusal names when many patches hit the blur search's bound,
// and the reasons' texts for given numbers.
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

TEST(CountsToString, CountThenReasonInTheGivenOrder) {
  EXPECT_EQ(CountsToString({{"without depth", 3}, {"across a depth edge", 12}}),
            "3 without depth, 12 across a depth edge");
  EXPECT_EQ(CountsToString({}), "");
}

// Two views by hand: 100 patches tried, 8 usable; 55 with too little
// texture (>= half: the leading cause), 8 at the search bound (>= 5 %: the
// fix), 2 without depth; 10 left unsearched by design (not a rejection).
TEST(PatchAccount, LeadingCauseSummaryAndFixByHand) {
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
  EXPECT_DOUBLE_EQ(account.max_radius_px, 10.0);
  EXPECT_EQ(account.leading_cause,
            "too little texture: 55 of 100 patches have texture too weak for "
            "the sensor noise; ");
  // Reasons summed over the views, in the order of their names, without the
  // unsearched ones.
  EXPECT_EQ(account.rejections,
            "8 blur at the search bound, 55 with texture too weak for the "
            "noise, 2 without depth");
  EXPECT_EQ(account.Summary(),
            " (patches over all views: 100 tried, 8 usable; 8 blur at the "
            "search bound, 55 with texture too weak for the noise, 2 without "
            "depth)");
  EXPECT_EQ(account.TypicalCauses(),
            "; patches over all views: 100 tried, 8 usable (8 blur at the "
            "search bound, 55 with texture too weak for the noise, 2 without "
            "depth). Typical causes: sensor noise too strong for the texture, "
            "too little defocus blur (small aperture, distant subjects), "
            "textureless surfaces");
  // 8 of 100 >= 5 %; the larger bound ceil(max(1.6 x 10, 10 + 2)) = 16.
  EXPECT_EQ(account.Fixes(),
            "; 8 of 100 patches have more blur than the search bound of 10 "
            "px: let the search reach farther with "
            "--DPScaleEstimator.max_radius_px 16");
}

TEST(PatchAccount, ThresholdsAtTheirEdges) {
  // Texture: 50 of 100 is half (a leading cause), 49 is not.
  EXPECT_NE(
      AccountPatches({{100, 0, {{kTextureTooWeak, 50}}, 5.0}}).leading_cause,
      "");
  EXPECT_EQ(
      AccountPatches({{100, 0, {{kTextureTooWeak, 49}}, 5.0}}).leading_cause,
      "");
  // The bound: 5 of 100 is 5 % (named), with ceil(max(1.6 x 12.75, 14.75))
  // = ceil(20.4) = 21 and the bound printed to 3 digits.
  EXPECT_EQ(
      AccountPatches({{100, 0, {{kBlurAtSearchBound, 5}}, 12.75}}).Fixes(),
      "; 5 of 100 patches have more blur than the search bound of 12.8 "
      "px: let the search reach farther with "
      "--DPScaleEstimator.max_radius_px 21");
  // No rejections: the summary has the counts only; nothing tried, no fix.
  const PatchAccount clean = AccountPatches({{10, 10, {}, 5.0}});
  EXPECT_EQ(clean.Summary(), " (patches over all views: 10 tried, 10 usable)");
  EXPECT_EQ(clean.rejections, "");
  EXPECT_EQ(AccountPatches({}).Fixes(), "");
}

TEST(UndeterminedScaleReason, TextForAGivenInterval) {
  // [0.3, 0.62] around 0.4213 spans 0.32 / 0.4213 = 76 % of it.
  EXPECT_EQ(UndeterminedScaleReason(0.4213, 0.3, 0.62, 0.32 / 0.4213, 0.3),
            "the data do not determine the scale: its bootstrap interval "
            "[0.3, 0.62] spans 76 % of the estimate 0.4213 (limit 30 %)");
}

TEST(CalibratedProfileOpenReason, NumbersOfTheInterval) {
  const std::string reason =
      CalibratedProfileOpenReason(0.22, 0.39, 0.28, 3.39, 0.3, false);
  EXPECT_EQ(reason.find("the DP profile's own uncertainty (+-22.0 %"), 0u)
      << reason;
  EXPECT_NE(reason.find("(estimate 0.3900), wider than the limit of 30 %. "),
            std::string::npos)
      << reason;
}

TEST(UnknownProfileReason, WithAndWithoutTheFitsReason) {
  EXPECT_EQ(UnknownProfileReason("", 0.5, 0.25, 1.5)
                .find("the sensor's DP profile is unknown: profiles "
                      "consistent with the data give scales from 0.25 to 1.5 "
                      "(estimate 0.5 with the profile used). Calibrate"),
            0u);
  const std::string with =
      UnknownProfileReason("3 bands fitted", 0.5, 0.25, 1.5);
  EXPECT_EQ(with.find("the sensor's DP profile is unknown: self-calibration: "
                      "3 bands fitted; profiles consistent"),
            0u)
      << with;
  EXPECT_NE(with.find("--DPScaleEstimator.psf_model calibrated"),
            std::string::npos);
}

TEST(DisagreementAdvice, BothCuesAndWhichToTrust) {
  // {valid, scale, ci_low, ci_high, num_views}
  const ScaleCue dp{true, 0.42, 0.40, 0.44, 0};
  const ScaleCue focus{true, 0.5, 0.48, 0.52, 3};
  // Covering both: [0.40, 0.52], 0.12 / 0.42 = 28.6 % of the DP scale.
  const double width = 0.12 / 0.42;
  const std::string calibrated =
      DisagreementAdvice(dp, focus, width, 0.1, true);
  EXPECT_EQ(calibrated.find("the DP data give 0.42 in [0.4, 0.44], the "
                            "recorded focus 0.5 in [0.48, 0.52]; an interval "
                            "covering both spans 28.6 % of the scale (limit "
                            "10.0 %). Trust the recorded focus if it was "
                            "measured"),
            0u)
      << calibrated;
  EXPECT_NE(calibrated.find("the profile was calibrated for this camera"),
            std::string::npos);
  const std::string fitted = DisagreementAdvice(dp, focus, width, 0.1, false);
  EXPECT_EQ(fitted.find("the profile was calibrated"), std::string::npos);
  EXPECT_NE(fitted.find("you calibrate the DP profile (colmap "
                        "dp_psf_calibrator)"),
            std::string::npos)
      << fitted;
  for (const std::string& advice : {calibrated, fitted}) {
    EXPECT_NE(advice.find("--DPScaleEstimator.pin_to_recorded_focus 0"),
              std::string::npos);
  }
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
