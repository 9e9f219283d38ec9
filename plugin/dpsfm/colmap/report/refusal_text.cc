#include "dpsfm/colmap/report/refusal_text.h"

#include <cmath>
#include <iomanip>
#include <sstream>

namespace dpsfm {
namespace {

// Short phrase for counts of rejected views ("with s <= 0").
const char* ViewRejectionPhrase(ViewRejection rejection) {
  switch (rejection) {
    case ViewRejection::kNone:
      return "used";
    case ViewRejection::kTooFewPatches:
      return "with too few reliable patches";
    case ViewRejection::kDegenerate:
      return "without depth variation among their patches";
    case ViewRejection::kNonPositiveScale:
      return "with s <= 0";
    case ViewRejection::kNonPositiveFocus:
      return "with focus distance <= 0 (or at infinity)";
    case ViewRejection::kFocusBelowFocalLength:
      return "with focus distance below the focal length";
    case ViewRejection::kSmallBlurRange:
      return "with blur range <= T_p (too little blur)";
    case ViewRejection::kPoorFit:
      return "whose blur does not follow their depth (poor single-view fit)";
    case ViewRejection::kFarFromMedian:
      return "farther from the median scale than the N_v kept";
  }
  return "?";
}

// The recorded focus could not settle the scale; `preceded`: a reason
// stands before it (then a disagreement is joined with "; ").
std::string CueRefusalText(const CueRefusal& cues, bool preceded) {
  std::ostringstream s;
  if (cues.cause == CueRefusalCause::kDisagree) {
    s << (preceded ? "; " : "")
      << "the two cues to the scale disagree: " << DisagreementAdviceText(cues);
  } else if (cues.cause == CueRefusalCause::kTooWide) {
    s << "; with the recorded focus of " << cues.focus.num_views
      << " view(s): " << cues.how << ", " << std::fixed << std::setprecision(1)
      << 100 * cues.width << " % wide, also over the limit of "
      << 100 * cues.limit << " %";
  }
  return s.str();
}

std::string CalibratedProfileOpenText(const OpenScale& open) {
  std::ostringstream s;
  s << "the DP profile's own uncertainty (+-" << std::fixed
    << std::setprecision(1) << 100 * open.profile_relative_uncertainty
    << " %: its calibration's and how far a calibration transfers to "
       "scenes) and the data's leave the scale between "
    << std::setprecision(4) << open.ci_low << " and " << open.ci_high
    << " (estimate " << open.scale << "), wider than the limit of "
    << std::setprecision(0) << 100 * open.limit << " %. "
    << (open.focus_recorded
            ? "Add views with more depth range, measure the focus "
              "distance with a tape (then set "
              "--DPScaleEstimator.recorded_focus_tolerance to its "
              "accuracy), "
            : "Record the focus distance (lens.csv "
              "focus_distance_m, or the camera's EXIF) so that the "
              "profile-free cue joins the DP data, add views with "
              "more depth range, ")
    << "or allow a wider interval with "
       "--DPScaleEstimator.max_scale_ci_relative_width";
  return s.str();
}

std::string UnknownProfileText(const OpenScale& open) {
  // The whole frame's fit in short (the report has every band's).
  std::string fit_reason = open.fit_reason;
  if (open.self_calibrated) {
    fit_reason += "; a fitted profile's strength is uncertain by +-" +
                  std::to_string(std::lround(100 * open.shape_uncertainty)) +
                  " % beyond the fit, for kernel shapes outside the family "
                  "that fit the patches as well";
  }
  std::ostringstream s;
  s << "the sensor's DP profile is unknown: "
    << (fit_reason.empty() ? "" : "self-calibration: " + fit_reason + "; ")
    << "profiles consistent with the data give scales from " << open.ci_low
    << " to " << open.ci_high << " (estimate " << open.scale
    << " with the profile used). Calibrate the camera's DP profile "
       "once with colmap dp_psf_calibrator (a textured plane at two or "
       "more distances) and run with --DPScaleEstimator.psf_model "
       "calibrated --DPScaleEstimator.psf_path FILE";
  return s.str();
}

std::string UndeterminedScaleText(const OpenScale& open) {
  std::ostringstream s;
  s << "the data do not determine the scale: its bootstrap interval ["
    << open.ci_low << ", " << open.ci_high << "] spans " << std::fixed
    << std::setprecision(0) << 100 * open.width << " % of the estimate "
    << std::setprecision(4) << open.scale << " (limit " << std::setprecision(0)
    << 100 * open.limit << " %)";
  return s.str();
}

}  // namespace

std::string LeadingCauseText(const PatchAccount& account) {
  if (!account.TextureLeads()) return "";
  std::ostringstream s;
  s << "too little texture: " << account.texture_too_weak << " of "
    << account.tried << " patches have texture too weak for the sensor noise; ";
  return s.str();
}

std::string PatchSummaryText(const PatchAccount& account) {
  std::ostringstream s;
  s << " (patches over all views: " << account.tried << " tried, "
    << account.usable << " usable";
  if (!account.rejections.empty()) {
    s << "; " << CountsToString(account.rejections);
  }
  s << ")";
  return s.str();
}

std::string TypicalCausesText(const PatchAccount& account) {
  std::ostringstream s;
  s << "; patches over all views: " << account.tried << " tried, "
    << account.usable << " usable";
  if (!account.rejections.empty()) {
    s << " (" << CountsToString(account.rejections) << ")";
  }
  s << ". Typical causes: sensor noise too strong for the texture, "
       "too little defocus blur (small aperture, distant subjects), "
       "textureless surfaces";
  return s.str();
}

std::string PatchFixesText(const PatchAccount& account) {
  if (!account.SearchBoundLimits()) return "";
  std::ostringstream s;
  s << "; " << account.at_search_bound << " of " << account.tried
    << " patches have more blur than the search bound of "
    << std::setprecision(3) << account.max_radius_px
    << " px: let the search reach farther with "
       "--DPScaleEstimator.max_radius_px "
    << account.LargerSearchBound();
  return s.str();
}

std::string LinearFailureText(const LinearFailure& failure) {
  switch (failure.cause) {
    case LinearFailureCause::kNone:
      return "";
    case LinearFailureCause::kNoViews:
      return "no views";
    case LinearFailureCause::kRankDeficient:
      return "the joint linear system of the selected views is rank deficient";
    case LinearFailureCause::kNonPositiveScale:
      return "the joint linear fit gives s <= 0";
    case LinearFailureCause::kNoViewSelected:
      break;
  }
  std::ostringstream s;
  s << "no view passed selection:";
  bool first = true;
  for (const auto& item : failure.view_rejections) {
    s << (first ? " " : ", ") << item.first
      << (first ? (item.first == 1 ? " view " : " views ") : " ");
    if (item.second == ViewRejection::kSmallBlurRange) {
      s << "with blur range <= " << failure.min_blur_range_px
        << " px (too little blur: depth range too shallow for the aperture, "
           "stopped down too far, or subject far beyond the focus)";
    } else {
      s << ViewRejectionPhrase(item.second);
    }
    first = false;
  }
  if (failure.SwappedViewsLikely()) {
    s << ". Blur that shrinks with depth in most views usually means the "
         "left and right DP views are swapped: run again with "
         "--DPScaleEstimator.swap_dp_views flipped (1 if it was 0)";
  }
  return s.str();
}

std::string OpenScaleText(const OpenScale& open) {
  std::ostringstream s;
  switch (open.cause) {
    case OpenScaleCause::kNone:
      break;
    case OpenScaleCause::kTooFewPatches:
      s << "too few usable patches for a scale (" << open.num_rows
        << " in the joint solve, need " << open.min_total_patches << ")";
      break;
    case OpenScaleCause::kNoInterval:
      s << "the scale's interval could not be measured ("
        << open.interval_status << "): a scale without one is not reported";
      break;
    case OpenScaleCause::kCalibratedProfile:
      s << CalibratedProfileOpenText(open);
      break;
    case OpenScaleCause::kUnknownProfile:
      s << UnknownProfileText(open);
      break;
    case OpenScaleCause::kWideInterval:
      s << UndeterminedScaleText(open);
      break;
  }
  return s.str();
}

std::string TranslatingDiskRejectionText(const TranslatingDiskRejection& disk) {
  std::ostringstream s;
  s << "the DP data reject the translating disk (--DPScaleEstimator."
       "psf_model translating_disk, the paper's model of another sensor): "
       "self-calibration fits "
    << disk.fit_summary;
  if (disk.factor_low <= disk.factor_high) {
    s << std::setprecision(3) << "; the profiles the data allow put the "
      << "scale at " << disk.factor_low << " to " << disk.factor_high
      << " times the disk's";
  }
  s << ". Run with --DPScaleEstimator.psf_model auto (the profile fitted "
       "to the data) or calibrated (colmap dp_psf_calibrator)";
  return s.str();
}

std::string DisagreementAdviceText(const CueRefusal& cues) {
  std::ostringstream s;
  s << std::setprecision(4) << "the DP data give " << cues.dp.scale << " in ["
    << cues.dp.ci_low << ", " << cues.dp.ci_high << "], the recorded focus "
    << cues.focus.scale << " in [" << cues.focus.ci_low << ", "
    << cues.focus.ci_high << "]; an interval covering both spans " << std::fixed
    << std::setprecision(1) << 100 * cues.width << " % of the scale (limit "
    << 100 * cues.limit << " %). Trust the recorded focus if it was measured "
    << "(a tape to the focal-plane mark): set "
       "--DPScaleEstimator.recorded_focus_tolerance to its accuracy. Trust "
       "the DP data if ";
  if (cues.calibrated) {
    s << "the profile was calibrated for this camera, lens and aperture and "
         "the recorded focus is the camera's own (a bracket, not a "
         "measurement): run with --DPScaleEstimator.pin_to_recorded_focus 0";
  } else {
    s << "the recorded focus is the camera's own (a bracket, not a "
         "measurement) and you calibrate the DP profile (colmap "
         "dp_psf_calibrator); then run with "
         "--DPScaleEstimator.pin_to_recorded_focus 0";
  }
  return s.str();
}

std::string RefusalText(const DPScaleRefusal& refusal) {
  const PatchAccount& patches = refusal.patches;
  switch (refusal.code) {
    case ScaleRefusal::kNone:
      return "";
    case ScaleRefusal::kNoViews:
      return "no DP views were given";
    case ScaleRefusal::kLinearStageThrew:
      return "linear stage failed: " + refusal.error;
    case ScaleRefusal::kTranslatingDiskRejected:
      return TranslatingDiskRejectionText(refusal.disk);
    case ScaleRefusal::kLinearStageFailed:
      return LeadingCauseText(patches) +
             LinearFailureText(refusal.linear_failure) +
             PatchSummaryText(patches) + PatchFixesText(patches);
    case ScaleRefusal::kScaleOpen:
      return LeadingCauseText(patches) + OpenScaleText(refusal.open) +
             CueRefusalText(refusal.cues, /*preceded=*/true) +
             (refusal.recorded_focus_missing
                  ? "; a recorded focus distance (lens.csv's "
                    "focus_distance_m, or the camera's EXIF) would give the "
                    "scale without the DP profile"
                  : "") +
             TypicalCausesText(patches) + PatchFixesText(patches);
    case ScaleRefusal::kCuesNotCombined:
      return CueRefusalText(refusal.cues, /*preceded=*/false);
  }
  return "";
}

std::string CombinationText(const DPScaleResult& result) {
  if (!result.dp_data_alone) return result.combination;
  return result.focus_cue.valid
             ? "the DP data alone (the recorded focus is evidence only: "
               "pin_to_recorded_focus 0)"
             : "the DP data alone (no recorded focus)";
}

std::string FocusCheckText(const DPScaleResult& result) {
  if (result.focus_check.empty()) return "";
  const std::string how = CombinationText(result);
  return how.empty() ? result.focus_check
                     : result.focus_check + ". The answer: " + how;
}

std::string PsfStatusText(const DPScaleResult& result) {
  return result.psf_rejected ? TranslatingDiskRejectionText(result.refusal.disk)
                             : result.psf_status;
}

}  // namespace dpsfm
