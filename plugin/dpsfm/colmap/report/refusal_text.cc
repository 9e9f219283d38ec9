#include "dpsfm/colmap/report/refusal_text.h"

#include <cctype>
#include <cmath>
#include <iomanip>
#include <sstream>
#include <utility>

namespace dpsfm {
namespace {

// A scale or a factor to 3 significant digits ("0.318").
std::string Num(double x) {
  std::ostringstream s;
  s << std::setprecision(3) << x;
  return s.str();
}

// A fraction as a percentage to 0.1, without a trailing ".0" ("71.4 %",
// "30 %"); under 1 %, to 2 significant digits ("0.01 %").
std::string Percent(double fraction) {
  std::ostringstream s;
  const double tenths = std::round(1000 * fraction);
  if (std::abs(100 * fraction) < 1) {
    s << std::setprecision(2) << 100 * fraction << " %";
  } else {
    s << std::fixed << std::setprecision(std::fmod(tenths, 10) == 0 ? 0 : 1)
      << tenths / 10 << " %";
  }
  return s.str();
}

// `text` cut at a space to at most `max` characters, "..." marking the cut.
std::string Shorten(const std::string& text, std::size_t max) {
  if (text.size() <= max) return text;
  if (max < 4) return text.substr(0, max);
  std::size_t cut = text.rfind(' ', max - 3);
  if (cut == std::string::npos || cut < max / 2) cut = max - 3;
  return text.substr(0, cut) + "...";
}

// A refusal's line: the cause, then the first two of the fixes ("" are
// skipped) that fit within kRefusalLineMaxChars ("<cause>. <Fix>; <fix>").
// `aside` (a secondary finding, "; ...") follows the cause only where it
// leaves room for the first fix.
std::string Line(const std::string& cause,
                 const std::vector<std::string>& fixes,
                 const std::string& aside = "") {
  std::string line = Shorten(cause, kRefusalLineMaxChars);
  std::vector<std::string> parts;
  for (const std::string& fix : fixes) {
    if (!fix.empty()) parts.push_back(fix);
  }
  if (!aside.empty() &&
      (parts.empty() || line.size() + aside.size() + 2 + parts[0].size() <=
                            kRefusalLineMaxChars)) {
    line = Shorten(line + aside, kRefusalLineMaxChars);
  }
  int added = 0;
  for (const std::string& fix : parts) {
    if (added == 2) break;
    std::string part = (added == 0 ? ". " : "; ") + fix;
    if (added == 0) part[2] = static_cast<char>(std::toupper(part[2]));
    if (line.size() + part.size() > kRefusalLineMaxChars) continue;
    line += part;
    ++added;
  }
  return line;
}

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
    << std::setprecision(3) << account.max_radius_px << " px: ";
  if (account.BoundAtProfileCoverage()) {
    s << "twice the blur the DP profile's calibration covered ("
      << account.profile_covered_radius_px
      << " px); a calibration capture farther from the focus would cover "
         "them";
  } else {
    s << "let the search reach farther with --DPScaleEstimator.max_radius_px "
      << account.LargerSearchBound();
  }
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

std::string DisagreementAdviceText(const CueRefusal& cues,
                                   bool dp_data_answer) {
  std::ostringstream s;
  s << std::setprecision(4) << "the DP data give " << cues.dp.scale << " in ["
    << cues.dp.ci_low << ", " << cues.dp.ci_high << "], the recorded focus "
    << cues.focus.scale << " in [" << cues.focus.ci_low << ", "
    << cues.focus.ci_high << "]; an interval covering both spans " << std::fixed
    << std::setprecision(1) << 100 * cues.width << " % of the scale (limit "
    << 100 * cues.limit << " %). Trust the recorded focus if it was measured "
    << "(a tape to the focal-plane mark): set "
       "--DPScaleEstimator.recorded_focus_tolerance to its accuracy.";
  if (!dp_data_answer) {
    s << " The DP data alone do not answer either (see below)";
    return s.str();
  }
  s << " Trust the DP data if ";
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

std::string DisagreementCauseText(const CueRefusal& cues) {
  return "the DP data and the recorded focus disagree: " + Num(cues.dp.scale) +
         " [" + Num(cues.dp.ci_low) + ", " + Num(cues.dp.ci_high) + "] vs " +
         Num(cues.focus.scale) + " [" + Num(cues.focus.ci_low) + ", " +
         Num(cues.focus.ci_high) + "] (" + Percent(cues.width) +
         " wide, limit " + Percent(cues.limit) + ")";
}

namespace {

// The fixes a refusal's line may name, each for one cause.
const char kCheckLensDataFix[] =
    "check the f-number and focus in lens.csv/EXIF";
const char kMeasuredFocusFix[] =
    "a measured focus: --DPScaleEstimator.recorded_focus_tolerance "
    "ACCURACY";
const char kTrustDPDataFix[] =
    "trust the DP data: --DPScaleEstimator.pin_to_recorded_focus 0";
const char kRecordFocusFix[] =
    "record the focus distance (lens.csv focus_distance_m, or EXIF)";
const char kMoreBlurFix[] =
    "more blur: a wider aperture, or views with more depth range";
const char kWiderLimitFix[] =
    "a wider limit: --DPScaleEstimator.max_scale_ci_relative_width";

// A larger blur-search bound, when the patches hit it.
std::string SearchBoundFix(const PatchAccount& patches) {
  if (!patches.SearchBoundLimits()) return "";
  const bool at_coverage = patches.BoundAtProfileCoverage();
  std::ostringstream s;
  if (at_coverage) {
    s << "a DP profile calibrated with more blur (a plane farther from the "
         "focus): ";
  } else {
    s << "search farther: --DPScaleEstimator.max_radius_px "
      << patches.LargerSearchBound() << " (";
  }
  s << patches.at_search_bound << " of " << patches.tried
    << " patches beyond the " << Num(patches.max_radius_px) << " px bound"
    << (at_coverage ? "" : ")");
  return s.str();
}

// "W of T patches have texture too weak for the noise; " when the weak
// texture leads (what follows it follows from it), else "".
std::string TextureLead(const PatchAccount& patches) {
  if (!patches.TextureLeads()) return "";
  return std::to_string(patches.texture_too_weak) + " of " +
         std::to_string(patches.tried) +
         " patches have texture too weak for the noise; ";
}

const char kTextureFix[] =
    "views of more textured surfaces, or 16-bit DP "
    "frames";

// LinearFailureText in short: at most two kinds of rejected views.
std::string LinearFailureCause(const LinearFailure& failure) {
  if (failure.cause != LinearFailureCause::kNoViewSelected) {
    return LinearFailureText(failure);
  }
  std::ostringstream s;
  s << "no view passed selection:";
  const auto& rejections = failure.view_rejections;
  for (std::size_t i = 0; i < rejections.size() && i < 2; ++i) {
    const int n = rejections[i].first;
    s << (i == 0 ? " " : ", ") << n
      << (i == 0 ? (n == 1 ? " view " : " views ") : " ");
    if (rejections[i].second == ViewRejection::kSmallBlurRange) {
      s << "with blur range <= " << failure.min_blur_range_px
        << " px (too little blur)";
    } else {
      s << ViewRejectionPhrase(rejections[i].second);
    }
  }
  if (rejections.size() > 2) {
    int more = 0;
    for (std::size_t i = 2; i < rejections.size(); ++i) {
      more += rejections[i].first;
    }
    s << ", " << more << " for other reasons";
  }
  return s.str();
}

// OpenScaleText in short.
std::string OpenScaleCauseText(const OpenScale& open) {
  switch (open.cause) {
    case OpenScaleCause::kNone:
      return "the DP data leave the scale open";
    case OpenScaleCause::kTooFewPatches:
      return OpenScaleText(open);
    case OpenScaleCause::kNoInterval:
      return "the scale's interval could not be measured (" +
             Shorten(open.interval_status, 80) + ")";
    case OpenScaleCause::kCalibratedProfile: {
      std::ostringstream s;
      s << "the DP profile's uncertainty (+-"
        << Percent(open.profile_relative_uncertainty)
        << ") leaves the scale in [" << Num(open.ci_low) << ", "
        << Num(open.ci_high) << "], " << Percent(open.width) << " wide (limit "
        << Percent(open.limit) << ")";
      return s.str();
    }
    case OpenScaleCause::kUnknownProfile:
      return "the DP profile is unknown: with the profiles the data allow, "
             "the interval is [" +
             Num(open.ci_low) + ", " + Num(open.ci_high) + "] (" +
             Percent(open.width) + " wide, limit " + Percent(open.limit) + ")";
    case OpenScaleCause::kWideInterval:
      return "the data do not determine the scale: its interval [" +
             Num(open.ci_low) + ", " + Num(open.ci_high) + "] spans " +
             Percent(open.width) + " of the estimate " + Num(open.scale) +
             " (limit " + Percent(open.limit) + ")";
  }
  return "";
}

std::string ScaleOpenLine(const DPScaleRefusal& refusal) {
  const OpenScale& open = refusal.open;
  const CueRefusal& cues = refusal.cues;
  const PatchAccount& patches = refusal.patches;
  // The recorded focus would have answered but for the disagreement: that
  // decided (the DP data alone stay open; which cue to trust, or the lens
  // data both rest on, is the fix).
  if (cues.cause == CueRefusalCause::kDisagree) {
    return Line(DisagreementCauseText(cues),
                {kCheckLensDataFix, kMeasuredFocusFix});
  }
  const std::string cause = TextureLead(patches) + OpenScaleCauseText(open);
  const char* texture_fix = patches.TextureLeads() ? kTextureFix : "";
  const std::string aside =
      cues.cause == CueRefusalCause::kTooWide
          ? "; with the recorded focus still " + Percent(cues.width) + " wide"
          : "";
  std::vector<std::string> fixes;
  switch (open.cause) {
    case OpenScaleCause::kCalibratedProfile:
      fixes = {texture_fix,
               open.focus_recorded ? kMeasuredFocusFix : kRecordFocusFix,
               kWiderLimitFix};
      break;
    case OpenScaleCause::kUnknownProfile:
      fixes = {texture_fix,
               "calibrate it (colmap dp_psf_calibrator), then "
               "--DPScaleEstimator.psf_model calibrated "
               "--DPScaleEstimator.psf_path FILE",
               refusal.recorded_focus_missing ? kRecordFocusFix : ""};
      break;
    case OpenScaleCause::kNone:
    case OpenScaleCause::kTooFewPatches:
    case OpenScaleCause::kNoInterval:
    case OpenScaleCause::kWideInterval:
      fixes = {SearchBoundFix(patches),
               texture_fix,
               refusal.recorded_focus_missing ? kRecordFocusFix : "",
               cues.cause == CueRefusalCause::kTooWide ? kMeasuredFocusFix : "",
               "add views with more depth range and texture"};
      break;
  }
  return Line(cause, fixes, aside);
}

std::string LinearStageFailedLine(const DPScaleRefusal& refusal) {
  const LinearFailure& failure = refusal.linear_failure;
  const PatchAccount& patches = refusal.patches;
  if (refusal.SmallBlurRangeOpenProfile()) {
    // Too little blur only as the assumed profile reads it: a weaker one,
    // which the data allow, reads the same frames' blur larger (a real
    // sensor's weak split read by the translating disk), and the data
    // cannot tell that from a capture with little blur.
    std::ostringstream cause;
    cause << TextureLead(patches) << LinearFailureCause(failure)
          << "; the DP profile is open: a weaker one reads it ";
    if (std::isfinite(refusal.blur_read_factor)) {
      cause << "up to " << std::fixed << std::setprecision(1)
            << refusal.blur_read_factor << " x larger";
    } else {
      cause << "larger without bound";
    }
    return Line(cause.str(),
                {"calibrate it: colmap dp_psf_calibrator", kMoreBlurFix});
  }
  std::vector<std::string> fixes;
  if (failure.SwappedViewsLikely()) {
    fixes.push_back(
        "blur shrinking with depth means swapped DP views: flip "
        "--DPScaleEstimator.swap_dp_views");
  }
  fixes.push_back(SearchBoundFix(patches));
  if (patches.TextureLeads()) fixes.push_back(kTextureFix);
  if (!failure.view_rejections.empty() &&
      failure.view_rejections.front().second ==
          ViewRejection::kSmallBlurRange) {
    fixes.push_back(kMoreBlurFix);
  }
  // Views swapped explain their s <= 0 better than the texture does.
  return Line((failure.SwappedViewsLikely() ? "" : TextureLead(patches)) +
                  LinearFailureCause(failure),
              fixes);
}

std::string CuesNotCombinedLine(const CueRefusal& cues) {
  if (cues.cause == CueRefusalCause::kDisagree) {
    return Line(DisagreementCauseText(cues),
                {kMeasuredFocusFix, kTrustDPDataFix});
  }
  return Line("with the recorded focus of " +
                  std::to_string(cues.focus.num_views) +
                  " view(s) the interval is " + Percent(cues.width) +
                  " wide, over the limit of " + Percent(cues.limit),
              {kMeasuredFocusFix,
               "the DP data alone answer with "
               "--DPScaleEstimator.pin_to_recorded_focus 0"});
}

// "patches over all views: T tried, U usable (<rejections>)".
std::string PatchCountsText(const PatchAccount& patches) {
  std::string s = "patches over all views: " + std::to_string(patches.tried) +
                  " tried, " + std::to_string(patches.usable) + " usable";
  if (!patches.rejections.empty()) {
    s += " (" + CountsToString(patches.rejections) + ")";
  }
  return s;
}

// The text without a leading "; " (the parts written to follow a reason).
std::string Unprefixed(const std::string& text) {
  return text.compare(0, 2, "; ") == 0 ? text.substr(2) : text;
}

// The account's lines on the patches: the leading cause, the counts, and a
// larger search bound (typical causes when the patches decided).
void AddPatchLines(const PatchAccount& patches,
                   bool typical_causes,
                   std::vector<std::string>* lines) {
  if (patches.tried == 0) return;
  const std::string leading = LeadingCauseText(patches);
  if (!leading.empty()) lines->push_back(leading.substr(0, leading.size() - 2));
  lines->push_back(typical_causes ? Unprefixed(TypicalCausesText(patches))
                                  : PatchCountsText(patches));
  const std::string bound = PatchFixesText(patches);
  if (!bound.empty()) lines->push_back(Unprefixed(bound));
}

const char kCheckLensDataAdvice[] =
    "Both cues rest on the views' lens data: check their f-number, focal "
    "length and focus distance (lens.csv, EXIF) against the capture, and "
    "that the DP profile was made for this lens at this aperture";

}  // namespace

std::string RefusalLine(const DPScaleRefusal& refusal) {
  switch (refusal.code) {
    case ScaleRefusal::kNone:
      return "";
    case ScaleRefusal::kNoViews:
      return "no DP views were given";
    case ScaleRefusal::kLinearStageThrew:
      return Line("linear stage failed: " + refusal.error, {});
    case ScaleRefusal::kTranslatingDiskRejected: {
      const TranslatingDiskRejection& disk = refusal.disk;
      std::string cause = "the DP data reject the translating disk";
      if (disk.factor_low <= disk.factor_high) {
        cause += ": the profiles they allow put the scale at " +
                 Num(disk.factor_low) + " to " + Num(disk.factor_high) +
                 " times the disk's";
      } else {
        cause +=
            " (self-calibration fits " + Shorten(disk.fit_summary, 80) + ")";
      }
      return Line(cause,
                  {"run with --DPScaleEstimator.psf_model auto or calibrated "
                   "(colmap dp_psf_calibrator)"});
    }
    case ScaleRefusal::kLinearStageFailed:
      return LinearStageFailedLine(refusal);
    case ScaleRefusal::kScaleOpen:
      return ScaleOpenLine(refusal);
    case ScaleRefusal::kCuesNotCombined:
      return CuesNotCombinedLine(refusal.cues);
  }
  return "";
}

std::vector<std::string> RefusalAccount(const DPScaleRefusal& refusal) {
  const PatchAccount& patches = refusal.patches;
  const CueRefusal& cues = refusal.cues;
  std::vector<std::string> lines;
  switch (refusal.code) {
    case ScaleRefusal::kNone:
      return lines;
    case ScaleRefusal::kNoViews:
      lines.push_back("no DP views were given");
      break;
    case ScaleRefusal::kLinearStageThrew:
      lines.push_back("linear stage failed: " + refusal.error);
      break;
    case ScaleRefusal::kTranslatingDiskRejected:
      lines.push_back(TranslatingDiskRejectionText(refusal.disk));
      AddPatchLines(patches, false, &lines);
      break;
    case ScaleRefusal::kLinearStageFailed:
      lines.push_back(LinearFailureText(refusal.linear_failure));
      AddPatchLines(patches, true, &lines);
      break;
    case ScaleRefusal::kScaleOpen: {
      const OpenScale& open = refusal.open;
      const bool disagree = cues.cause == CueRefusalCause::kDisagree;
      if (disagree) {
        lines.push_back("the DP data and the recorded focus disagree: " +
                        DisagreementAdviceText(cues, /*dp_alone=*/false));
        lines.push_back(kCheckLensDataAdvice);
        lines.push_back("without the recorded focus: " + OpenScaleText(open));
      } else {
        lines.push_back(OpenScaleText(open));
        if (cues.cause == CueRefusalCause::kTooWide) {
          lines.push_back(Unprefixed(CueRefusalText(cues, true)));
        }
      }
      if (refusal.recorded_focus_missing) {
        lines.push_back(
            "a recorded focus distance (lens.csv's focus_distance_m, or the "
            "camera's EXIF) would give the scale without the DP profile");
      }
      AddPatchLines(
          patches,
          !disagree && (open.cause == OpenScaleCause::kTooFewPatches ||
                        open.cause == OpenScaleCause::kNoInterval ||
                        open.cause == OpenScaleCause::kWideInterval),
          &lines);
      break;
    }
    case ScaleRefusal::kCuesNotCombined:
      if (cues.cause == CueRefusalCause::kDisagree) {
        lines.push_back("the DP data and the recorded focus disagree: " +
                        DisagreementAdviceText(cues));
        lines.push_back(kCheckLensDataAdvice);
      } else {
        lines.push_back(Unprefixed(CueRefusalText(cues, true)) +
                        "; the DP data alone answer with "
                        "--DPScaleEstimator.pin_to_recorded_focus 0");
      }
      AddPatchLines(patches, false, &lines);
      break;
  }
  return lines;
}

std::string CombinationText(const DPScaleResult& result) {
  if (!result.cues.dp_data_alone) return result.cues.combination;
  return result.cues.focus.valid
             ? "the DP data alone (the recorded focus is evidence only: "
               "pin_to_recorded_focus 0)"
             : "the DP data alone (no recorded focus)";
}

std::string FocusCheckText(const DPScaleResult& result) {
  if (result.cues.focus_check.empty()) return "";
  const std::string how = CombinationText(result);
  return how.empty() ? result.cues.focus_check
                     : result.cues.focus_check + ". The answer: " + how;
}

std::string PsfStatusText(const DPScaleResult& result) {
  return result.psf.rejected ? TranslatingDiskRejectionText(result.refusal.disk)
                             : result.psf.status;
}

}  // namespace dpsfm
