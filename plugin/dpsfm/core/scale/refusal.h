// Refusals (DPScaleEstimator::Estimate): why no scale is reported, as a code
// and the numbers that decided it, where the patches of all views went, and
// what the data say would help. No words for users here: the COLMAP layer
// (colmap/report/refusal_text) words a refusal with the options' names,
// which the core does not know.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "dpsfm/core/scale/linear_estimator.h"
#include "dpsfm/core/scale/scale_cues.h"

namespace dpsfm {

// "3 without depth, 12 across a depth edge" from (reason, count) pairs.
std::string CountsToString(
    const std::vector<std::pair<std::string, int>>& counts);

// Where the patches of all views went.
struct PatchAccount {
  int tried = 0;
  int usable = 0;
  // (reason, count) over all views, in the reasons' alphabetical order,
  // except patches the blur search skipped by design (no defect of the
  // data).
  std::vector<std::pair<std::string, int>> rejections;
  // Patches whose texture was too weak for the noise.
  int texture_too_weak = 0;
  // Patches whose blur lies beyond the search bound, and the largest bound
  // of the views (px of the working frame, DPScaleOptions' blur.max_radius_px).
  int at_search_bound = 0;
  double max_radius_px = 0;
  // The blur a measured profile's calibration covered
  // (PatchGeometryOptions::profile_covered_radius_px; 0: none).
  double profile_covered_radius_px = 0;

  // At least half the patches had texture too weak for the noise: the
  // leading cause (the views' other symptoms, e.g. a small blur range,
  // follow from it).
  bool TextureLeads() const;
  // At least 5 % of the patches hit the search bound (of a known, positive
  // size): a larger bound may turn the refusal into an answer.
  bool SearchBoundLimits() const;
  // That larger bound: 1.6 times the largest (at least 2 px more), rounded
  // up. A bound 1.6 times larger reaches the blur of points about that much
  // farther from the focal plane (in inverse depth).
  int LargerSearchBound() const;
  // The bound already reaches twice the blur the profile's calibration
  // covered: beyond it the profile's magnified kernels are a guess (on the
  // R6 II's box/002 a 16 px bound read the near boxes' ~7 px blur as 12 px
  // and moved the answer 33 % low), so the fix is a calibration capture
  // with more blur, not a larger bound. The free function of the same name
  // on this account's bound and covered blur.
  bool BoundAtProfileCoverage() const;
};

// Whether a search bound of bound_px reaches twice the blur a measured
// profile's calibration covered (covered_px; 0: no such profile), where a
// larger bound would read patches through guessed kernels
// (PatchAccount::BoundAtProfileCoverage).
bool BoundAtProfileCoverage(double bound_px, double covered_px);

// Per view: (tried, usable, (reason, count) pairs).
struct ViewPatchCounts {
  int tried = 0;
  int usable = 0;
  std::vector<std::pair<std::string, int>> rejections;
  double max_radius_px = 0;  // the view's search bound
};
PatchAccount AccountPatches(const std::vector<ViewPatchCounts>& views);

// SelfCalibration::kCheck: the data determine another profile than the
// given translating disk.
struct TranslatingDiskRejection {
  // The fit in short (the whole frame's reason, or the bands' summary).
  std::string fit_summary;
  // The factors by which the profiles the data allow would move the scale
  // against the disk's (low > high when not bounded).
  double factor_low = 1, factor_high = 1;
};

// Why the DP data alone leave the scale open, in the order they are tested.
enum class OpenScaleCause {
  kNone,
  kTooFewPatches,      // num_rows < min_total_patches
  kNoInterval,         // the bootstrap measured no interval
  kCalibratedProfile,  // a given profile's uncertainty (with the data's)
  kUnknownProfile,     // self-calibration: the profiles the data allow
  kWideInterval,       // the data's interval is wider than the limit
};

struct OpenScale {
  OpenScaleCause cause = OpenScaleCause::kNone;
  // kTooFewPatches: rows of the joint solve and ScaleIntervalOptions::
  // min_total_patches.
  int num_rows = 0;
  int min_total_patches = 0;
  // kNoInterval: why (LinearEstimate::interval_status).
  std::string interval_status;
  // The linear stage's scale and interval (with every systematic term and
  // the profile's factors), the interval's width relative to the scale, and
  // ScaleIntervalOptions::max_scale_ci_relative_width.
  double scale = 0, ci_low = 0, ci_high = 0;
  double width = 0, limit = 0;
  // kCalibratedProfile: ScaleIntervalOptions::profile_relative_uncertainty,
  // and whether a recorded focus already joins the DP data (then recording
  // one is not the advice).
  double profile_relative_uncertainty = 0;
  bool focus_recorded = false;
  // kUnknownProfile: the self-calibration's reason (may be ""), and, when a
  // fitted profile replaced the given one, the relative uncertainty of its
  // strength beyond the fit (SelfCalibrationOptions::shape_uncertainty).
  std::string fit_reason;
  bool self_calibrated = false;
  double shape_uncertainty = 0;
};

// How the recorded focus failed to settle the scale with the DP data
// (AdoptCombinedCues).
enum class CueRefusalCause {
  kNone,      // not tried (no usable recorded focus, or not pinned)
  kDisagree,  // the cues disagree and an interval covering both is too wide
  kTooWide,   // combined, the interval is still too wide
};

struct CueRefusal {
  CueRefusalCause cause = CueRefusalCause::kNone;
  ScaleCue dp, focus;
  // The combined interval's width relative to its scale, and the limit.
  double width = 0, limit = 0;
  // kDisagree: the DP profile was given (calibrated), not fitted.
  bool calibrated = false;
  // kTooWide: how the cues were combined (CombinedScale::how).
  std::string how;
};

enum class ScaleRefusal {
  kNone,                     // a scale was reported
  kNoViews,                  // no DP views were given
  kLinearStageThrew,         // error
  kTranslatingDiskRejected,  // disk
  kLinearStageFailed,        // linear_failure (and patches)
  kScaleOpen,                // open, cues, recorded_focus_missing, patches
  kCuesNotCombined,          // the DP data answered; cues
};

// The code in a few words, without the numbers (core-only tools' logs and
// test messages; users read colmap/report/refusal_text's sentence).
const char* ScaleRefusalName(ScaleRefusal code);

// Why no scale is reported, with everything its wording needs.
struct DPScaleRefusal {
  ScaleRefusal code = ScaleRefusal::kNone;
  std::string error;  // kLinearStageThrew: what the linear stage threw
  TranslatingDiskRejection disk;
  LinearFailure linear_failure;
  OpenScale open;
  CueRefusal cues;
  // kScaleOpen: the recorded focus is pinned, yet no selected view recorded
  // one (which would give the scale without the DP profile).
  bool recorded_focus_missing = false;
  PatchAccount patches;
  // kLinearStageFailed with a self-calibrated profile: how many times
  // larger than the profile used reads them the profiles the data allow
  // would read the blur (1 / DPPsfResult::scale_factor_low; +inf
  // when they are not bounded; 1 with a given profile). A view's blur range
  // under T_p is then "too little blur" only when this is near 1.
  double blur_read_factor = 1;

  // The views' blur ranges fell under T_p, but with a profile the data do
  // not determine: they could read larger (by more than 1.5 times).
  bool SmallBlurRangeOpenProfile() const;
};

}  // namespace dpsfm
