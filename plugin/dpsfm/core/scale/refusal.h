// Refusal reasons (DPScaleEstimator::Estimate): where the patches of all
// views went, and the messages that say why no scale is reported, in words
// a user can act on. No decisions are made here, only the wording.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "dpsfm/core/scale/scale_cues.h"

namespace dpsfm {

// "3 without depth, 12 across a depth edge" from (reason, count) pairs.
std::string CountsToString(
    const std::vector<std::pair<std::string, int>>& counts);

struct PatchAccount {
  int tried = 0;
  int usable = 0;
  // The reasons over all views, except patches the blur search skipped by
  // design (no defect of the data); "" if none.
  std::string rejections;
  // "too little texture: ...; " when at least half the patches had texture
  // too weak for the noise (the views' other symptoms, e.g. a small blur
  // range, follow from it); else "".
  std::string leading_cause;

  // " (patches over all views: N tried, M usable; <rejections>)".
  std::string Summary() const;
  // Patches whose blur lies at the search bound, and the largest bound of
  // the views (px of the working frame, as --DPScaleEstimator.max_radius_px).
  int at_search_bound = 0;
  double max_radius_px = 0;

  // "; patches over all views: ... . Typical causes: ..." (the tail of a
  // refusal for an undetermined scale).
  std::string TypicalCauses() const;
  // The options that may turn the refusal into an answer, as "; ..." or "":
  // a larger search bound when at least 5 % of the patches hit it.
  std::string Fixes() const;
};

// Per view: (tried, usable, (reason, count) pairs).
struct ViewPatchCounts {
  int tried = 0;
  int usable = 0;
  std::vector<std::pair<std::string, int>> rejections;
  double max_radius_px = 0;  // the view's search bound
};
PatchAccount AccountPatches(const std::vector<ViewPatchCounts>& views);

// Why the interval leaves the scale open (the bootstrap interval spans
// `width` of the estimate, over the limit).
std::string UndeterminedScaleReason(
    double scale, double ci_low, double ci_high, double width, double limit);

// The DP profile's own uncertainty leaves the scale open: a calibrated
// profile's (+-relative_uncertainty), or, with self-calibration, an unknown
// profile (fit_reason: the self-calibration's reason, may be "").
// `focus_recorded`: a recorded focus distance already joins the DP data
// (then recording one is not the advice).
std::string CalibratedProfileOpenReason(double relative_uncertainty,
                                        double scale,
                                        double ci_low,
                                        double ci_high,
                                        double limit,
                                        bool focus_recorded);
std::string UnknownProfileReason(const std::string& fit_reason,
                                 double scale,
                                 double ci_low,
                                 double ci_high);

// An explicitly chosen translating disk that the data reject: the fit's
// summary, and the factors by which the profiles they allow would move the
// scale against the disk's (low > high when not bounded).
std::string RejectedTranslatingDiskReason(const std::string& fit_summary,
                                          double factor_low,
                                          double factor_high);

// The DP data and the recorded focus disagree and an interval covering
// both is `width` of the scale, over `limit`: both cues, and which to trust
// when (`calibrated`: the DP profile was given, not fitted to these data).
std::string DisagreementAdvice(const ScaleCue& dp,
                               const ScaleCue& focus,
                               double width,
                               double limit,
                               bool calibrated);

}  // namespace dpsfm
