#include "dpsfm/core/scale/refusal.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <sstream>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/blur/patch_selection.h"

namespace dpsfm {

std::string CountsToString(
    const std::vector<std::pair<std::string, int>>& counts) {
  std::ostringstream s;
  bool first = true;
  for (const auto& c : counts) {
    s << (first ? "" : ", ") << c.second << " " << c.first;
    first = false;
  }
  return s.str();
}

PatchAccount AccountPatches(const std::vector<ViewPatchCounts>& views) {
  PatchAccount account;
  std::map<std::string, int> rejections;
  for (const ViewPatchCounts& v : views) {
    account.tried += v.tried;
    account.usable += v.usable;
    account.max_radius_px = std::max(account.max_radius_px, v.max_radius_px);
    for (const auto& r : v.rejections) {
      if (r.first == kLeftUnsearched) continue;
      rejections[r.first] += r.second;
    }
  }
  if (!rejections.empty()) {
    account.rejections =
        CountsToString(std::vector<std::pair<std::string, int>>(
            rejections.begin(), rejections.end()));
  }
  account.at_search_bound = rejections[kBlurAtSearchBound];
  const int weak = rejections[kTextureTooWeak];
  if (weak > 0 && weak >= 0.5 * account.tried) {
    std::ostringstream cause;
    cause << "too little texture: " << weak << " of " << account.tried
          << " patches have texture too weak for the sensor noise; ";
    account.leading_cause = cause.str();
  }
  return account;
}

std::string PatchAccount::Summary() const {
  std::ostringstream s;
  s << " (patches over all views: " << tried << " tried, " << usable
    << " usable";
  if (!rejections.empty()) s << "; " << rejections;
  s << ")";
  return s.str();
}

std::string PatchAccount::TypicalCauses() const {
  std::ostringstream s;
  s << "; patches over all views: " << tried << " tried, " << usable
    << " usable";
  if (!rejections.empty()) s << " (" << rejections << ")";
  s << ". Typical causes: sensor noise too strong for the texture, "
       "too little defocus blur (small aperture, distant subjects), "
       "textureless surfaces";
  return s.str();
}

std::string PatchAccount::Fixes() const {
  if (tried == 0 || at_search_bound < 0.05 * tried || !(max_radius_px > 0)) {
    return "";
  }
  // A bound 1.6 times larger reaches the blur of points about that much
  // farther from the focal plane (in inverse depth).
  const int larger = static_cast<int>(
      std::ceil(std::max(1.6 * max_radius_px, max_radius_px + 2)));
  std::ostringstream s;
  s << "; " << at_search_bound << " of " << tried
    << " patches have more blur than the search bound of "
    << std::setprecision(3) << max_radius_px
    << " px: let the search reach farther with "
       "--DPScaleEstimator.max_radius_px "
    << larger;
  return s.str();
}

std::string UndeterminedScaleReason(
    double scale, double ci_low, double ci_high, double width, double limit) {
  std::ostringstream s;
  s << "the data do not determine the scale: its bootstrap interval [" << ci_low
    << ", " << ci_high << "] spans " << std::fixed << std::setprecision(0)
    << 100 * width << " % of the estimate " << std::setprecision(4) << scale
    << " (limit " << std::setprecision(0) << 100 * limit << " %)";
  return s.str();
}

std::string CalibratedProfileOpenReason(double relative_uncertainty,
                                        double scale,
                                        double ci_low,
                                        double ci_high,
                                        double limit,
                                        bool focus_recorded) {
  std::ostringstream s;
  s << "the DP profile's own uncertainty (+-" << std::fixed
    << std::setprecision(1) << 100 * relative_uncertainty
    << " %: its calibration's and how far a calibration transfers to "
       "scenes) and the data's leave the scale between "
    << std::setprecision(4) << ci_low << " and " << ci_high << " (estimate "
    << scale << "), wider than the limit of " << std::setprecision(0)
    << 100 * limit << " %. "
    << (focus_recorded ? "Add views with more depth range, measure the focus "
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

std::string UnknownProfileReason(const std::string& fit_reason,
                                 double scale,
                                 double ci_low,
                                 double ci_high) {
  std::ostringstream s;
  // The whole frame's fit in short (the report has every band's).
  s << "the sensor's DP profile is unknown: "
    << (fit_reason.empty() ? "" : "self-calibration: " + fit_reason + "; ")
    << "profiles consistent with the data give scales from " << ci_low << " to "
    << ci_high << " (estimate " << scale
    << " with the profile used). Calibrate the camera's DP profile "
       "once with colmap dp_psf_calibrator (a textured plane at two or "
       "more distances) and run with --DPScaleEstimator.psf_model "
       "calibrated --DPScaleEstimator.psf_path FILE";
  return s.str();
}

std::string RejectedTranslatingDiskReason(const std::string& fit_summary,
                                          double factor_low,
                                          double factor_high) {
  std::ostringstream s;
  s << "the DP data reject the translating disk (--DPScaleEstimator."
       "psf_model translating_disk, the paper's model of another sensor): "
       "self-calibration fits "
    << fit_summary;
  if (factor_low <= factor_high) {
    s << std::setprecision(3) << "; the profiles the data allow put the "
      << "scale at " << factor_low << " to " << factor_high
      << " times the disk's";
  }
  s << ". Run with --DPScaleEstimator.psf_model auto (the profile fitted "
       "to the data) or calibrated (colmap dp_psf_calibrator)";
  return s.str();
}

std::string DisagreementAdvice(const ScaleCue& dp,
                               const ScaleCue& focus,
                               double width,
                               double limit,
                               bool calibrated) {
  std::ostringstream s;
  s << std::setprecision(4) << "the DP data give " << dp.scale << " in ["
    << dp.ci_low << ", " << dp.ci_high << "], the recorded focus "
    << focus.scale << " in [" << focus.ci_low << ", " << focus.ci_high
    << "]; an interval covering both spans " << std::fixed
    << std::setprecision(1) << 100 * width << " % of the scale (limit "
    << 100 * limit << " %). Trust the recorded focus if it was measured "
    << "(a tape to the focal-plane mark): set "
       "--DPScaleEstimator.recorded_focus_tolerance to its accuracy. Trust "
       "the DP data if ";
  if (calibrated) {
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

}  // namespace dpsfm
