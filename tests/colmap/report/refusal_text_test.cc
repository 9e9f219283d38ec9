// The words of a refusal (colmap/report/refusal_text.h) for hand-made
// refusals: each part's text for given numbers, the options it names, and
// the whole sentence of each refusal code.
#include "dpsfm/colmap/report/refusal_text.h"

#include <string>

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
            " (patches over all views: 100 tried, 8 usable; 8 blur at the "
            "search bound, 55 with texture too weak for the noise, 2 without "
            "depth)");
  EXPECT_EQ(TypicalCausesText(account),
            "; patches over all views: 100 tried, 8 usable (8 blur at the "
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

// Whole sentences: the parts in their order.
TEST(RefusalText, EachCodeInFull) {
  DPScaleRefusal refusal;
  EXPECT_EQ(RefusalText(refusal), "");
  refusal.code = ScaleRefusal::kNoViews;
  EXPECT_EQ(RefusalText(refusal), "no DP views were given");
  refusal.code = ScaleRefusal::kLinearStageThrew;
  refusal.error = "bad lens";
  EXPECT_EQ(RefusalText(refusal), "linear stage failed: bad lens");

  refusal.patches = HandMadeAccount();
  refusal.code = ScaleRefusal::kLinearStageFailed;
  refusal.linear_failure.cause = LinearFailureCause::kNonPositiveScale;
  EXPECT_EQ(
      RefusalText(refusal),
      LeadingCauseText(refusal.patches) + "the joint linear fit gives s <= 0" +
          PatchSummaryText(refusal.patches) + PatchFixesText(refusal.patches));

  refusal.code = ScaleRefusal::kScaleOpen;
  refusal.open.cause = OpenScaleCause::kTooFewPatches;
  refusal.open.num_rows = 8;
  refusal.open.min_total_patches = 10;
  refusal.recorded_focus_missing = true;
  EXPECT_EQ(RefusalText(refusal),
            "too little texture: 55 of 100 patches have texture too weak for "
            "the sensor noise; too few usable patches for a scale (8 in the "
            "joint solve, need 10); a recorded focus distance (lens.csv's "
            "focus_distance_m, or the camera's EXIF) would give the scale "
            "without the DP profile" +
                TypicalCausesText(refusal.patches) +
                PatchFixesText(refusal.patches));
  // With the recorded focus tried: the disagreement follows the reason.
  refusal.recorded_focus_missing = false;
  refusal.cues = Disagreement(true);
  const std::string open = RefusalText(refusal);
  EXPECT_NE(open.find("need 10); the two cues to the scale disagree: the DP "
                      "data give 0.42"),
            std::string::npos)
      << open;
  // Too wide even combined.
  refusal.cues.cause = CueRefusalCause::kTooWide;
  refusal.cues.how = "their mean";
  refusal.cues.width = 0.456;
  refusal.cues.limit = 0.3;
  EXPECT_NE(RefusalText(refusal).find(
                "need 10); with the recorded focus of 3 view(s): their mean, "
                "45.6 % wide, also over the limit of 30.0 %; patches over"),
            std::string::npos)
      << RefusalText(refusal);

  // The DP data answered, the recorded focus could not join them: the
  // disagreement alone (and the too-wide text as it always read, with its
  // leading "; ").
  refusal.code = ScaleRefusal::kCuesNotCombined;
  refusal.cues = Disagreement(false);
  EXPECT_EQ(RefusalText(refusal),
            "the two cues to the scale disagree: " +
                DisagreementAdviceText(refusal.cues));
  refusal.cues.cause = CueRefusalCause::kTooWide;
  refusal.cues.how = "their mean";
  refusal.cues.width = 0.456;
  refusal.cues.limit = 0.3;
  EXPECT_EQ(RefusalText(refusal),
            "; with the recorded focus of 3 view(s): their mean, 45.6 % wide, "
            "also over the limit of 30.0 %");
}

TEST(PsfStatusText, ARejectedDiskReadsAsItsRefusal) {
  DPScaleResult result;
  result.psf_status = "self-calibration kept the translating disk (fits)";
  EXPECT_EQ(PsfStatusText(result), result.psf_status);
  result.psf_status.clear();
  result.psf_rejected = true;
  result.refusal.code = ScaleRefusal::kTranslatingDiskRejected;
  result.refusal.disk = {"p 2.2 determined", 2, 1};
  EXPECT_EQ(PsfStatusText(result), RefusalText(result.refusal));
  EXPECT_EQ(PsfStatusText(result).find("the DP data reject the translating "
                                       "disk"),
            0u);
}

TEST(CombinationText, TheCuesOrWhyTheDPDataAnsweredAlone) {
  DPScaleResult result;
  EXPECT_EQ(CombinationText(result), "");
  result.combination = "the cues agree (...): their mean";
  EXPECT_EQ(CombinationText(result), "the cues agree (...): their mean");
  result.combination.clear();
  result.dp_data_alone = true;
  EXPECT_EQ(CombinationText(result), "the DP data alone (no recorded focus)");
  result.focus_cue.valid = true;
  EXPECT_EQ(CombinationText(result),
            "the DP data alone (the recorded focus is evidence only: "
            "pin_to_recorded_focus 0)");
}

TEST(FocusCheckText, TheComparisonThenTheAnswer) {
  DPScaleResult result;
  result.dp_data_alone = true;
  // No recorded focus: no check, whatever the answer.
  EXPECT_EQ(FocusCheckText(result), "");
  result.focus_check =
      "the recorded focus distances of 2 used view(s) give a "
      "scale of 0.5";
  result.focus_cue.valid = true;
  EXPECT_EQ(FocusCheckText(result),
            "the recorded focus distances of 2 used view(s) give a scale of "
            "0.5. The answer: the DP data alone (the recorded focus is "
            "evidence only: pin_to_recorded_focus 0)");
  // A refused run has no answer to name.
  result.dp_data_alone = false;
  EXPECT_EQ(FocusCheckText(result), result.focus_check);
}

}  // namespace
}  // namespace dpsfm
