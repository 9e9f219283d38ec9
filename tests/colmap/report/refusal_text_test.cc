// The words of a refusal (colmap/report/refusal_text.h) for hand-made
// refusals: each part's text for given numbers, the options it names, and
// for each refusal code its first line (the cause with its numbers and at
// most two fixes, within 300 characters as an error line) and its account.
#include "dpsfm/colmap/report/refusal_text.h"

#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/blur/patch_selection.h"

namespace dpsfm {
namespace {

// Two views by hand: 100 patches tried, 8 usable; 55 with too little
// texture (>= half: the leading cause), 8 at the search bound (>= 5 %: the
// fix), 2 without depth; 10 left unsearched by design (not a rejection).
PatchAccount HandMadeAccount() {
  const ViewPatchCounts a{
      60,
      5,
      {{kTextureTooWeak, 40}, {kLeftUnsearched, 10}, {"without depth", 2}},
      10.0};
  const ViewPatchCounts b{
      40, 3, {{kTextureTooWeak, 15}, {kBlurAtSearchBound, 8}}, 8.0};
  return AccountPatches({a, b});
}

OpenScale CalibratedOpen(bool focus_recorded) {
  OpenScale open;
  open.cause = OpenScaleCause::kCalibratedProfile;
  open.profile_relative_uncertainty = 0.22;
  open.scale = 0.39;
  open.ci_low = 0.28;
  open.ci_high = 3.39;
  open.limit = 0.3;
  open.focus_recorded = focus_recorded;
  return open;
}

// {valid, scale, ci_low, ci_high, num_views}; covering both: [0.40, 0.52],
// 0.12 / 0.42 = 28.6 % of the DP scale.
CueRefusal Disagreement(bool calibrated) {
  CueRefusal cues;
  cues.cause = CueRefusalCause::kDisagree;
  cues.dp = {true, 0.42, 0.40, 0.44, 0};
  cues.focus = {true, 0.5, 0.48, 0.52, 3};
  cues.width = 0.12 / 0.42;
  cues.limit = 0.1;
  cues.calibrated = calibrated;
  return cues;
}

TEST(PatchAccountText, LeadingCauseSummaryAndFixByHand) {
  const PatchAccount account = HandMadeAccount();
  EXPECT_EQ(LeadingCauseText(account),
            "too little texture: 55 of 100 patches have texture too weak for "
            "the sensor noise; ");
  EXPECT_EQ(PatchSummaryText(account),
            " (patches over all views: 100 tried, 8 usable; 8 blur beyond the "
            "search bound, 55 with texture too weak for the noise, 2 without "
            "depth)");
  EXPECT_EQ(TypicalCausesText(account),
            "; patches over all views: 100 tried, 8 usable (8 blur beyond the "
            "search bound, 55 with texture too weak for the noise, 2 without "
            "depth). Typical causes: sensor noise too strong for the texture, "
            "too little defocus blur (small aperture, distant subjects), "
            "textureless surfaces");
  // 8 of 100 >= 5 %; the larger bound ceil(max(1.6 x 10, 10 + 2)) = 16.
  EXPECT_EQ(PatchFixesText(account),
            "; 8 of 100 patches have more blur than the search bound of 10 "
            "px: let the search reach farther with "
            "--DPScaleEstimator.max_radius_px 16");
}

TEST(PatchAccountText, ThresholdsAtTheirEdges) {
  // Texture: 50 of 100 is half (a leading cause), 49 is not.
  EXPECT_NE(LeadingCauseText(
                AccountPatches({{100, 0, {{kTextureTooWeak, 50}}, 5.0}})),
            "");
  EXPECT_EQ(LeadingCauseText(
                AccountPatches({{100, 0, {{kTextureTooWeak, 49}}, 5.0}})),
            "");
  // The bound: 5 of 100 is 5 % (named), with ceil(max(1.6 x 12.75, 14.75))
  // = ceil(20.4) = 21 and the bound printed to 3 digits.
  EXPECT_EQ(PatchFixesText(
                AccountPatches({{100, 0, {{kBlurAtSearchBound, 5}}, 12.75}})),
            "; 5 of 100 patches have more blur than the search bound of 12.8 "
            "px: let the search reach farther with "
            "--DPScaleEstimator.max_radius_px 21");
  // 4 of 100 < 5 %: no fix named.
  EXPECT_EQ(PatchFixesText(
                AccountPatches({{100, 50, {{kBlurAtSearchBound, 4}}, 6.5}})),
            "");
  // No rejections: the summary has the counts only; nothing tried, no fix.
  const PatchAccount clean = AccountPatches({{10, 10, {}, 5.0}});
  EXPECT_EQ(PatchSummaryText(clean),
            " (patches over all views: 10 tried, 10 usable)");
  EXPECT_EQ(PatchFixesText(AccountPatches({})), "");
}

TEST(OpenScaleText, UndeterminedForAGivenInterval) {
  // [0.3, 0.62] around 0.4213 spans 0.32 / 0.4213 = 76 % of it.
  OpenScale open;
  open.cause = OpenScaleCause::kWideInterval;
  open.scale = 0.4213;
  open.ci_low = 0.3;
  open.ci_high = 0.62;
  open.width = 0.32 / 0.4213;
  open.limit = 0.3;
  EXPECT_EQ(OpenScaleText(open),
            "the data do not determine the scale: its bootstrap interval "
            "[0.3, 0.62] spans 76 % of the estimate 0.4213 (limit 30 %)");
}

TEST(OpenScaleText, TooFewPatchesAndNoInterval) {
  OpenScale open;
  open.cause = OpenScaleCause::kTooFewPatches;
  open.num_rows = 7;
  open.min_total_patches = 10;
  EXPECT_EQ(OpenScaleText(open),
            "too few usable patches for a scale (7 in the joint solve, need "
            "10)");
  open.cause = OpenScaleCause::kNoInterval;
  open.interval_status = "num_bootstrap is 0";
  EXPECT_EQ(OpenScaleText(open),
            "the scale's interval could not be measured (num_bootstrap is 0): "
            "a scale without one is not reported");
  open.cause = OpenScaleCause::kNone;
  EXPECT_EQ(OpenScaleText(open), "");
}

TEST(OpenScaleText, CalibratedProfileAdvisesRecordingTheFocusOnlyWithoutOne) {
  const std::string without = OpenScaleText(CalibratedOpen(false));
  EXPECT_NE(without.find("Record the focus distance"), std::string::npos);
  EXPECT_NE(without.find("between 0.2800 and 3.3900"), std::string::npos)
      << without;
  const std::string with = OpenScaleText(CalibratedOpen(true));
  EXPECT_EQ(with.find("Record the focus distance"), std::string::npos) << with;
  EXPECT_NE(with.find("--DPScaleEstimator.recorded_focus_tolerance to its "
                      "accuracy"),
            std::string::npos);
}

TEST(OpenScaleText, CalibratedProfileNumbersOfTheInterval) {
  EXPECT_EQ(OpenScaleText(CalibratedOpen(false)),
            "the DP profile's own uncertainty (+-22.0 %: its calibration's "
            "and how far a calibration transfers to scenes) and the data's "
            "leave the scale between 0.2800 and 3.3900 (estimate 0.3900), "
            "wider than the limit of 30 %. Record the focus distance "
            "(lens.csv focus_distance_m, or the camera's EXIF) so that the "
            "profile-free cue joins the DP data, add views with more depth "
            "range, or allow a wider interval with "
            "--DPScaleEstimator.max_scale_ci_relative_width");
}

TEST(OpenScaleText, UnknownProfileWithAndWithoutTheFitsReason) {
  OpenScale open;
  open.cause = OpenScaleCause::kUnknownProfile;
  open.scale = 0.5;
  open.ci_low = 0.25;
  open.ci_high = 1.5;
  EXPECT_EQ(OpenScaleText(open),
            "the sensor's DP profile is unknown: profiles consistent with the "
            "data give scales from 0.25 to 1.5 (estimate 0.5 with the profile "
            "used). Calibrate the camera's DP profile once with colmap "
            "dp_psf_calibrator (a textured plane at two or more distances) "
            "and run with --DPScaleEstimator.psf_model calibrated "
            "--DPScaleEstimator.psf_path FILE");
  open.fit_reason = "3 bands fitted";
  const std::string with = OpenScaleText(open);
  EXPECT_EQ(with.find("the sensor's DP profile is unknown: self-calibration: "
                      "3 bands fitted; profiles consistent"),
            0u)
      << with;
  // A fitted profile: its shape's uncertainty, +-lround(100 x 0.125) = 13 %.
  open.self_calibrated = true;
  open.shape_uncertainty = 0.125;
  const std::string fitted = OpenScaleText(open);
  EXPECT_EQ(fitted.find("the sensor's DP profile is unknown: "
                        "self-calibration: 3 bands fitted; a fitted "
                        "profile's strength is uncertain by +-13 % beyond "
                        "the fit, for kernel shapes outside the family that "
                        "fit the patches as well; profiles consistent"),
            0u)
      << fitted;
}

TEST(DisagreementAdviceText, BothCuesAndWhichToTrust) {
  const std::string calibrated = DisagreementAdviceText(Disagreement(true));
  EXPECT_EQ(calibrated.find("the DP data give 0.42 in [0.4, 0.44], the "
                            "recorded focus 0.5 in [0.48, 0.52]; an interval "
                            "covering both spans 28.6 % of the scale (limit "
                            "10.0 %). Trust the recorded focus if it was "
                            "measured"),
            0u)
      << calibrated;
  EXPECT_NE(calibrated.find("the profile was calibrated for this camera"),
            std::string::npos);
  const std::string fitted = DisagreementAdviceText(Disagreement(false));
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

TEST(LinearFailureText, ViewsByRejectionAndTheSwapAdvice) {
  LinearFailure failure;
  failure.cause = LinearFailureCause::kNoViewSelected;
  failure.min_blur_range_px = 2;
  failure.view_rejections = {{9, ViewRejection::kSmallBlurRange},
                             {3, ViewRejection::kNonPositiveScale}};
  EXPECT_EQ(LinearFailureText(failure),
            "no view passed selection: 9 views with blur range <= 2 px (too "
            "little blur: depth range too shallow for the aperture, stopped "
            "down too far, or subject far beyond the focus), 3 with s <= 0");
  failure.view_rejections = {{1, ViewRejection::kNonPositiveScale}};
  EXPECT_EQ(LinearFailureText(failure),
            "no view passed selection: 1 view with s <= 0. Blur that shrinks "
            "with depth in most views usually means the left and right DP "
            "views are swapped: run again with "
            "--DPScaleEstimator.swap_dp_views flipped (1 if it was 0)");
  failure.cause = LinearFailureCause::kRankDeficient;
  EXPECT_EQ(LinearFailureText(failure),
            "the joint linear system of the selected views is rank deficient");
  failure.cause = LinearFailureCause::kNoViews;
  EXPECT_EQ(LinearFailureText(failure), "no views");
}

TEST(TranslatingDiskRejectionText, FactorsOnlyWhenBounded) {
  TranslatingDiskRejection disk{"p 2.2 determined", 0.41234, 0.62};
  EXPECT_EQ(TranslatingDiskRejectionText(disk),
            "the DP data reject the translating disk "
            "(--DPScaleEstimator.psf_model translating_disk, the paper's "
            "model of another sensor): self-calibration fits p 2.2 "
            "determined; the profiles the data allow put the scale at 0.412 "
            "to 0.62 times the disk's. Run with --DPScaleEstimator.psf_model "
            "auto (the profile fitted to the data) or calibrated (colmap "
            "dp_psf_calibrator)");
  disk.factor_low = 2;
  disk.factor_high = 1;
  EXPECT_EQ(TranslatingDiskRejectionText(disk).find("times the disk's"),
            std::string::npos);
}

// The error line a refusal's line becomes (dp_scale_estimator's).
std::string ErrorLine(const std::string& line) {
  return "ERROR: dp_scale_estimator: no scale: " + line +
         "; nothing was changed";
}

// How many options a text names.
int CountOptions(const std::string& text) {
  int n = 0;
  for (size_t at = text.find("--"); at != std::string::npos;
       at = text.find("--", at + 2)) {
    ++n;
  }
  return n;
}

// The first line's contract: within the limit (and its error line within
// 300 characters), led by `cause`, naming at most two options.
void ExpectShortLine(const std::string& line, const std::string& cause) {
  EXPECT_LE(line.size(), kRefusalLineMaxChars) << line;
  EXPECT_LE(ErrorLine(line).size(), 300u) << line;
  EXPECT_EQ(line.rfind(cause, 0), 0u)
      << "'" << cause << "' does not lead: " << line;
  EXPECT_LE(CountOptions(line), 2) << line;
  for (const char* buried : {"Typical causes", "patches over all views"}) {
    EXPECT_EQ(line.find(buried), std::string::npos) << line;
  }
}

// The issue's refusal: the DP data (a calibrated profile leaving them
// +-22.4 % open) and the recorded focus disagree, 0.318 against 0.357.
// The hull of both intervals, [0.25, 0.42] around 0.318, is 0.17 / 0.318 =
// 53.5 % of the scale.
DPScaleRefusal IssueDisagreement() {
  DPScaleRefusal refusal;
  refusal.code = ScaleRefusal::kScaleOpen;
  refusal.open = CalibratedOpen(true);
  refusal.open.profile_relative_uncertainty = 0.224;
  refusal.open.scale = 0.318;
  refusal.open.ci_low = 0.25;
  refusal.open.ci_high = 0.42;
  refusal.open.width = 0.17 / 0.318;
  refusal.cues.cause = CueRefusalCause::kDisagree;
  refusal.cues.dp = {true, 0.318, 0.25, 0.42, 0};
  refusal.cues.focus = {true, 0.357, 0.33, 0.385, 1};
  refusal.cues.width = 0.17 / 0.318;
  refusal.cues.limit = 0.3;
  refusal.cues.calibrated = true;
  refusal.patches = AccountPatches(
      {{1134,
        173,
        {{"across a depth edge", 173}, {kBlurAtSearchBound, 114}},
        4.93}});
  return refusal;
}

TEST(RefusalLine, TheDisagreementLeadsWithBothCuesAndTwoFixes) {
  const DPScaleRefusal refusal = IssueDisagreement();
  const std::string line = RefusalLine(refusal);
  EXPECT_EQ(line,
            "the DP data and the recorded focus disagree: 0.318 [0.25, "
            "0.42] vs 0.357 [0.33, 0.385] (53.5 % wide, limit 30 %). Check "
            "the f-number and focus in lens.csv/EXIF; a measured focus: "
            "--DPScaleEstimator.recorded_focus_tolerance ACCURACY");
  ExpectShortLine(line,
                  "the DP data and the recorded focus disagree: 0.318 "
                  "[0.25, 0.42] vs 0.357 [0.33, 0.385]");
  // What did not decide stays out of the line: the profile's width, the
  // search bound, the remedies for other causes.
  for (const char* other : {"uncertainty",
                            "max_radius_px",
                            "max_scale_ci_relative_width",
                            "pin_to_recorded_focus"}) {
    EXPECT_EQ(line.find(other), std::string::npos) << other;
  }
}

TEST(RefusalAccount, TheDisagreementInFullWithTheOtherCauses) {
  const std::vector<std::string> account = RefusalAccount(IssueDisagreement());
  ASSERT_EQ(account.size(), 5u);
  // The cause first, with both intervals and the advice on which to trust
  // (not the DP data: alone they leave the scale open).
  EXPECT_EQ(account[0],
            "the DP data and the recorded focus disagree: the DP data give "
            "0.318 in [0.25, 0.42], the recorded focus 0.357 in [0.33, "
            "0.385]; an interval covering both spans 53.5 % of the scale "
            "(limit 30.0 %). Trust the recorded focus if it was measured (a "
            "tape to the focal-plane mark): set "
            "--DPScaleEstimator.recorded_focus_tolerance to its accuracy. "
            "The DP data alone do not answer either (see below)");
  EXPECT_EQ(account[1].find("Both cues rest on the views' lens data: check "
                            "their f-number"),
            0u)
      << account[1];
  EXPECT_EQ(account[2].find("without the recorded focus: the DP profile's "
                            "own uncertainty (+-22.4 %"),
            0u)
      << account[2];
  EXPECT_EQ(account[3],
            "patches over all views: 1134 tried, 173 usable (173 across a "
            "depth edge, 114 blur beyond the search bound)");
  // 114 of 1134 >= 5 %: ceil(max(1.6 x 4.93, 6.93)) = 8.
  EXPECT_EQ(account[4],
            "114 of 1134 patches have more blur than the search bound of "
            "4.93 px: let the search reach farther with "
            "--DPScaleEstimator.max_radius_px 8");
  for (const std::string& line : account) {
    EXPECT_EQ(line.find("Typical causes"), std::string::npos) << line;
  }
}

// Every kind of refusal: its line leads with the cause and its numbers,
// names at most two options and fits; its account holds the rest.
TEST(RefusalLine, EachKindLeadsWithItsCauseWithinTheLimit) {
  DPScaleRefusal refusal;
  EXPECT_EQ(RefusalLine(refusal), "");
  EXPECT_TRUE(RefusalAccount(refusal).empty());

  refusal.code = ScaleRefusal::kNoViews;
  EXPECT_EQ(RefusalLine(refusal), "no DP views were given");

  // An exception's text of any length is cut to fit; the account keeps it.
  refusal.code = ScaleRefusal::kLinearStageThrew;
  refusal.error = "bad lens";
  EXPECT_EQ(RefusalLine(refusal), "linear stage failed: bad lens");
  refusal.error = std::string(400, 'x');
  ExpectShortLine(RefusalLine(refusal), "linear stage failed: xxx");
  EXPECT_EQ(RefusalAccount(refusal),
            std::vector<std::string>{"linear stage failed: " + refusal.error});

  // The translating disk: the factors (to 3 digits), one option.
  refusal.code = ScaleRefusal::kTranslatingDiskRejected;
  refusal.disk = {std::string(300, 'f'), 0.41234, 0.62};
  EXPECT_EQ(RefusalLine(refusal),
            "the DP data reject the translating disk: the profiles they "
            "allow put the scale at 0.412 to 0.62 times the disk's. Run with "
            "--DPScaleEstimator.psf_model auto or calibrated (colmap "
            "dp_psf_calibrator)");
  refusal.disk.factor_low = 2;
  refusal.disk.factor_high = 1;
  ExpectShortLine(RefusalLine(refusal),
                  "the DP data reject the translating disk (self-calibration "
                  "fits fff");
  EXPECT_EQ(RefusalAccount(refusal).front(),
            TranslatingDiskRejectionText(refusal.disk));

  // The linear stage: the two largest kinds of rejected views, the rest
  // counted; swapped views (most with s <= 0) lead over the texture, and
  // their fix comes first (the search bound's does not fit beside it).
  refusal.code = ScaleRefusal::kLinearStageFailed;
  refusal.patches = HandMadeAccount();
  refusal.linear_failure.cause = LinearFailureCause::kNoViewSelected;
  refusal.linear_failure.min_blur_range_px = 2;
  refusal.linear_failure.view_rejections = {
      {9, ViewRejection::kNonPositiveScale},
      {3, ViewRejection::kSmallBlurRange},
      {2, ViewRejection::kPoorFit},
      {1, ViewRejection::kDegenerate}};
  ASSERT_TRUE(refusal.linear_failure.SwappedViewsLikely());
  const std::string linear = RefusalLine(refusal);
  EXPECT_EQ(linear,
            "no view passed selection: 9 views with s <= 0, 3 with blur "
            "range <= 2 px (too little blur), 3 for other reasons. Blur "
            "shrinking with depth means swapped DP views: flip "
            "--DPScaleEstimator.swap_dp_views");
  ExpectShortLine(linear, "no view passed selection: 9 views with s <= 0");
  // The account: every kind, the swap advice, the patches, typical causes
  // and the search bound.
  std::vector<std::string> account = RefusalAccount(refusal);
  ASSERT_EQ(account.size(), 4u);
  EXPECT_EQ(account[0], LinearFailureText(refusal.linear_failure));
  EXPECT_NE(account[0].find("1 without depth variation"), std::string::npos);
  EXPECT_EQ(account[1],
            "too little texture: 55 of 100 patches have texture too weak for "
            "the sensor noise");
  EXPECT_NE(account[2].find("Typical causes"), std::string::npos);
  EXPECT_NE(account[3].find("--DPScaleEstimator.max_radius_px 16"),
            std::string::npos);
  // Without the swap the weak texture leads (55 of 100 >= half), and the
  // search bound (8 of 100 at the 10 px bound) is the first fix.
  const std::string texture =
      "55 of 100 patches have texture too weak for the noise; ";
  refusal.linear_failure.view_rejections = {
      {9, ViewRejection::kSmallBlurRange}};
  EXPECT_EQ(RefusalLine(refusal),
            texture +
                "no view passed selection: 9 views with blur range <= 2 px "
                "(too little blur). Search farther: "
                "--DPScaleEstimator.max_radius_px 16 (8 of 100 patches "
                "beyond the 10 px bound)");
  // The same small blur ranges under a self-calibrated profile the data
  // leave open: too little blur as the profile assumed reads it, which a
  // weaker one would read 3 times larger (or without bound), so the line
  // says so and names the calibration first.
  refusal.blur_read_factor = 3;
  EXPECT_EQ(RefusalLine(refusal),
            texture +
                "no view passed selection: 9 views with blur range <= 2 px "
                "(too little blur); the DP profile is open: a weaker one "
                "reads it up to 3.0 x larger. Calibrate it: colmap "
                "dp_psf_calibrator");
  refusal.blur_read_factor = std::numeric_limits<double>::infinity();
  EXPECT_NE(RefusalLine(refusal).find("larger without bound"),
            std::string::npos);
  refusal.blur_read_factor = 1.2;  // the profile nearly pinned
  EXPECT_EQ(RefusalLine(refusal).find("profile open"), std::string::npos);
  refusal.blur_read_factor = 1;
  refusal.linear_failure.cause = LinearFailureCause::kNonPositiveScale;
  ExpectShortLine(RefusalLine(refusal),
                  texture + "the joint linear fit gives s <= 0");

  // The scale left open, by each cause.
  refusal.code = ScaleRefusal::kScaleOpen;
  refusal.patches = HandMadeAccount();
  refusal.open.cause = OpenScaleCause::kTooFewPatches;
  refusal.open.num_rows = 8;
  refusal.open.min_total_patches = 10;
  refusal.recorded_focus_missing = true;
  EXPECT_EQ(RefusalLine(refusal),
            texture +
                "too few usable patches for a scale (8 in the joint solve, "
                "need 10). Search farther: --DPScaleEstimator.max_radius_px "
                "16 (8 of 100 patches beyond the 10 px bound)");
  account = RefusalAccount(refusal);
  EXPECT_EQ(account.front(),
            "too few usable patches for a scale (8 in the joint solve, need "
            "10)");
  EXPECT_NE(account[1].find("a recorded focus distance"), std::string::npos);
  refusal.recorded_focus_missing = false;

  refusal.open.cause = OpenScaleCause::kNoInterval;
  refusal.open.interval_status = "num_bootstrap is 0";
  ExpectShortLine(RefusalLine(refusal),
                  texture +
                      "the scale's interval could not be measured "
                      "(num_bootstrap is 0)");
  // Texture that does not lead (49 of 100) is left to the account.
  refusal.patches = AccountPatches(
      {{100, 40, {{kTextureTooWeak, 49}, {kBlurAtSearchBound, 8}}, 10.0}});
  EXPECT_EQ(RefusalLine(refusal),
            "the scale's interval could not be measured (num_bootstrap is "
            "0). Search farther: --DPScaleEstimator.max_radius_px 16 (8 of "
            "100 patches beyond the 10 px bound); add views with more depth "
            "range and texture");
  // A bound at twice the blur a measured profile's calibration covered: a
  // larger one would read its patches through guessed kernels, so the fix
  // is a calibration with more blur, never a larger bound.
  refusal.patches.profile_covered_radius_px = 5;
  EXPECT_EQ(RefusalLine(refusal),
            "the scale's interval could not be measured (num_bootstrap is "
            "0). A DP profile calibrated with more blur (a plane farther "
            "from the focus): 8 of 100 patches beyond the 10 px bound; add "
            "views with more depth range and texture");
  refusal.patches.profile_covered_radius_px = 6;  // 10 < 2 x 6 - 0.5
  EXPECT_NE(RefusalLine(refusal).find("max_radius_px 16"), std::string::npos);
  refusal.patches.profile_covered_radius_px = 0;

  refusal.open = CalibratedOpen(false);
  refusal.open.width = (3.39 - 0.28) / 0.39;  // 797.4 %
  EXPECT_EQ(RefusalLine(refusal),
            "the DP profile's uncertainty (+-22 %) leaves the scale in [0.28, "
            "3.39], 797.4 % wide (limit 30 %). Record the focus distance "
            "(lens.csv focus_distance_m, or EXIF); a wider limit: "
            "--DPScaleEstimator.max_scale_ci_relative_width");
  refusal.open.focus_recorded = true;
  ExpectShortLine(RefusalLine(refusal),
                  "the DP profile's uncertainty (+-22 %) leaves the scale in "
                  "[0.28, 3.39], 797.4 % wide");
  EXPECT_NE(RefusalLine(refusal).find("recorded_focus_tolerance"),
            std::string::npos);

  // An unknown profile; with the recorded focus too wide as well (the
  // aside gives way to the fix).
  refusal.open.cause = OpenScaleCause::kUnknownProfile;
  refusal.open.fit_reason = std::string(200, 'r');
  refusal.open.scale = 1.00132;
  refusal.open.ci_low = 0;
  refusal.open.ci_high = 1.02575;
  refusal.open.width = 1.02575 / 1.00132;
  refusal.cues = CueRefusal();
  refusal.cues.cause = CueRefusalCause::kTooWide;
  refusal.cues.focus.num_views = 1;
  refusal.cues.how = "the recorded focus alone";
  refusal.cues.width = 0.303;
  refusal.cues.limit = 0.3;
  const std::string unknown = RefusalLine(refusal);
  ExpectShortLine(unknown,
                  "the DP profile is unknown: with the profiles the data "
                  "allow, the interval is [0, 1.03] (102.4 % wide, limit 30 "
                  "%)");
  EXPECT_NE(unknown.find("colmap dp_psf_calibrator), then "
                         "--DPScaleEstimator.psf_model calibrated "
                         "--DPScaleEstimator.psf_path FILE"),
            std::string::npos)
      << unknown;
  account = RefusalAccount(refusal);
  EXPECT_NE(account[0].find(refusal.open.fit_reason), std::string::npos);
  EXPECT_EQ(account[1].find("with the recorded focus of 1 view(s): the "
                            "recorded focus alone, 30.3 % wide"),
            0u)
      << account[1];

  // A textureless scene: the weak texture leads (3495 of 5597 >= half)
  // whatever left the scale open, and its fix comes first.
  refusal.cues = CueRefusal();
  refusal.open.ci_high = std::numeric_limits<double>::infinity();
  refusal.open.width = std::numeric_limits<double>::infinity();
  refusal.patches =
      AccountPatches({{5597, 262, {{kTextureTooWeak, 3495}}, 10.0}});
  EXPECT_EQ(RefusalLine(refusal),
            "3495 of 5597 patches have texture too weak for the noise; the DP "
            "profile is unknown: with the profiles the data allow, the "
            "interval is [0, inf] (inf % wide, limit 30 %). Views of more "
            "textured surfaces, or 16-bit DP frames");
  refusal.patches = AccountPatches(
      {{100, 40, {{kTextureTooWeak, 49}, {kBlurAtSearchBound, 8}}, 10.0}});

  refusal.open.cause = OpenScaleCause::kWideInterval;
  refusal.open.scale = 0.4213;
  refusal.open.ci_low = 0.3;
  refusal.open.ci_high = 0.62;
  refusal.open.width = 0.32 / 0.4213;
  refusal.cues = CueRefusal();
  ExpectShortLine(RefusalLine(refusal),
                  "the data do not determine the scale: its interval [0.3, "
                  "0.62] spans 76 % of the estimate 0.421 (limit 30 %)");

  // The DP data answered; the recorded focus could not join them.
  refusal.code = ScaleRefusal::kCuesNotCombined;
  refusal.cues = Disagreement(false);
  EXPECT_EQ(RefusalLine(refusal),
            "the DP data and the recorded focus disagree: 0.42 [0.4, 0.44] "
            "vs 0.5 [0.48, 0.52] (28.6 % wide, limit 10 %). A "
            "measured focus: --DPScaleEstimator.recorded_focus_tolerance "
            "ACCURACY; trust the DP data: "
            "--DPScaleEstimator.pin_to_recorded_focus 0");
  ExpectShortLine(RefusalLine(refusal),
                  "the DP data and the recorded focus disagree");
  EXPECT_EQ(RefusalAccount(refusal).front(),
            "the DP data and the recorded focus disagree: " +
                DisagreementAdviceText(refusal.cues));
  refusal.cues.cause = CueRefusalCause::kTooWide;
  refusal.cues.width = 0.456;
  ExpectShortLine(RefusalLine(refusal),
                  "with the recorded focus of 3 view(s) the interval is 45.6 "
                  "% wide, over the limit of 10 %");
}

// Extreme numbers never push the line past its limit.
TEST(RefusalLine, LongNumbersStayWithinTheLimit) {
  DPScaleRefusal refusal = IssueDisagreement();
  refusal.cues.dp.scale = 1.23456789e-7;
  refusal.cues.focus.scale = 9.87654321e+12;
  refusal.cues.width = 123456.789;
  refusal.cues.limit = 0.00012345;
  for (ScaleRefusal code :
       {ScaleRefusal::kScaleOpen, ScaleRefusal::kCuesNotCombined}) {
    refusal.code = code;
    ExpectShortLine(RefusalLine(refusal),
                    "the DP data and the recorded focus disagree: 1.23e-07 "
                    "[0.25, 0.42] vs 9.88e+12");
  }
}

TEST(PsfStatusText, ARejectedDiskReadsAsItsRefusal) {
  DPScaleResult result;
  result.psf.status = "self-calibration kept the translating disk (fits)";
  EXPECT_EQ(PsfStatusText(result), result.psf.status);
  result.psf.status.clear();
  result.psf.rejected = true;
  result.refusal.code = ScaleRefusal::kTranslatingDiskRejected;
  result.refusal.disk = {"p 2.2 determined", 2, 1};
  EXPECT_EQ(PsfStatusText(result), RefusalAccount(result.refusal).front());
  EXPECT_EQ(PsfStatusText(result).find("the DP data reject the translating "
                                       "disk"),
            0u);
}

TEST(CombinationText, TheCuesOrWhyTheDPDataAnsweredAlone) {
  DPScaleResult result;
  EXPECT_EQ(CombinationText(result), "");
  result.cues.combination = "the cues agree (...): their mean";
  EXPECT_EQ(CombinationText(result), "the cues agree (...): their mean");
  result.cues.combination.clear();
  result.cues.dp_data_alone = true;
  EXPECT_EQ(CombinationText(result), "the DP data alone (no recorded focus)");
  result.cues.focus.valid = true;
  EXPECT_EQ(CombinationText(result),
            "the DP data alone (the recorded focus is evidence only: "
            "pin_to_recorded_focus 0)");
}

TEST(FocusCheckText, TheComparisonThenTheAnswer) {
  DPScaleResult result;
  result.cues.dp_data_alone = true;
  // No recorded focus: no check, whatever the answer.
  EXPECT_EQ(FocusCheckText(result), "");
  result.cues.focus_check =
      "the recorded focus distances of 2 used view(s) give a "
      "scale of 0.5";
  result.cues.focus.valid = true;
  EXPECT_EQ(FocusCheckText(result),
            "the recorded focus distances of 2 used view(s) give a scale of "
            "0.5. The answer: the DP data alone (the recorded focus is "
            "evidence only: pin_to_recorded_focus 0)");
  // A refused run has no answer to name.
  result.cues.dp_data_alone = false;
  EXPECT_EQ(FocusCheckText(result), result.cues.focus_check);
}

}  // namespace
}  // namespace dpsfm
