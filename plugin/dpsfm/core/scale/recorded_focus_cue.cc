// DPScaleEstimator's two cues and their combination: the DP data's own
// estimate, the recorded focus distances' (profile-free), and how the answer
// is formed from them (scale_cues.h), or refused.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <random>
#include <sstream>

#include "dpsfm/core/scale/scale_estimator.h"
#include "dpsfm/core/scale/scale_estimator_data.h"
#include "dpsfm/core/util/statistics.h"

namespace dpsfm {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

ScaleCue DPScaleEstimator::DPCue(const LinearEstimate& linear) const {
  ScaleCue cue;
  cue.scale = linear.scale;
  cue.ci_low = linear.scale_ci_low;
  cue.ci_high = linear.scale_ci_high;
  cue.valid = linear.num_rows >= options_.interval.min_total_patches &&
              linear.scale > 0 && cue.ci_low > 0 &&
              std::isfinite(cue.ci_high) && cue.ci_high >= cue.ci_low;
  return cue;
}

ScaleCue DPScaleEstimator::RecordedFocusCue(const LinearEstimate& linear,
                                            double lens_geometry) const {
  ScaleCue cue;
  // The views that carry the cue: used, with a recorded focus and a fitted
  // focal plane g' (where the disparity changes sign, whatever the profile).
  std::vector<int> views;
  std::vector<double> object_m;
  std::vector<double> brackets;
  for (int i : linear.selected_views) {
    const DPLensData& lens = views_[i]->lens;
    if (!std::isfinite(lens.recorded_focus_mm) ||
        !(linear.views[i].focus_model > 0)) {
      continue;
    }
    try {
      object_m.push_back(
          FocusObjectDistanceMm(lens.recorded_focus_mm, lens.focal_length_mm) /
          1000);
      views.push_back(i);
      brackets.push_back(std::isfinite(lens.recorded_focus_bracket)
                             ? lens.recorded_focus_bracket
                             : 0.0);
    } catch (const std::invalid_argument&) {
      // Nearer than the lens can focus: no evidence.
    }
  }
  if (views.empty()) return cue;
  auto scale_of = [&](auto focus_model_of) {
    std::vector<double> scales;
    for (size_t k = 0; k < views.size(); ++k) {
      const double g = focus_model_of(views[k]);
      if (g > 0) scales.push_back(object_m[k] / g);
    }
    return scales.empty() ? kNaN : Percentile(scales, 0.5);
  };
  const double scale =
      scale_of([&](int i) { return linear.views[i].focus_model; });
  std::vector<double> resampled;
  const size_t num_resamples =
      linear.views[views[0]].focus_model_samples.size();
  for (size_t b = 0; b < num_resamples; ++b) {
    const double sb = scale_of([&](int i) {
      const auto& samples = linear.views[i].focus_model_samples;
      return b < samples.size() ? samples[b] : kNaN;
    });
    if (std::isfinite(sb)) resampled.push_back(sb);
  }
  if (resampled.size() < 10 || !(scale > 0)) return cue;
  const double alpha = 0.5 * (1.0 - options_.linear.confidence_level);
  double lo = std::min(scale, Percentile(resampled, alpha));
  double hi = std::max(scale, Percentile(resampled, 1 - alpha));
  // The record's own accuracy (the tolerance, and the window a camera
  // records as its focus: Canon's maker note gives a bracket, not a
  // distance), the estimator's systematic term and the lens geometry's, in
  // quadrature with the bootstrap's halves.
  const double bracket = Percentile(brackets, 0.5);
  const double sys =
      scale *
      std::sqrt(std::pow(options_.interval.recorded_focus_tolerance, 2) +
                bracket * bracket +
                std::pow(options_.interval.scale_systematic_uncertainty, 2) +
                lens_geometry * lens_geometry);
  cue.scale = scale;
  cue.ci_low = scale - std::hypot(scale - lo, sys);
  cue.ci_high = scale + std::hypot(hi - scale, sys);
  cue.num_views = static_cast<int>(views.size());
  cue.valid = cue.ci_low > 0 && std::isfinite(cue.ci_high);
  return cue;
}

bool DPScaleEstimator::RecordedFocusMissing(
    const LinearEstimate& linear) const {
  for (int i : linear.selected_views) {
    if (std::isfinite(views_[i]->lens.recorded_focus_mm)) return false;
  }
  return true;
}

bool DPScaleEstimator::AdoptCombinedCues(const LinearEstimate& linear,
                                         DPScaleResult* result,
                                         CueRefusal* refusal) const {
  const CombinedScale combined =
      CombineScaleCues(result->cues.dp, result->cues.focus);
  const double width = (combined.ci_high - combined.ci_low) / combined.scale;
  result->cues.agreement = combined.agreement;
  std::ostringstream s;
  s << std::setprecision(4);
  if (!(width <= options_.interval.max_scale_ci_relative_width) ||
      !(combined.ci_low > 0)) {
    refusal->cause = combined.agreement == CueAgreement::kDisagree
                         ? CueRefusalCause::kDisagree
                         : CueRefusalCause::kTooWide;
    refusal->dp = result->cues.dp;
    refusal->focus = result->cues.focus;
    refusal->width = width;
    refusal->limit = options_.interval.max_scale_ci_relative_width;
    refusal->calibrated =
        options_.self_calibration.mode == SelfCalibrationOptions::Mode::kOff;
    refusal->how = combined.how;
    return false;
  }
  result->cues.combined = true;
  result->cues.scale_from_recorded_focus =
      combined.agreement == CueAgreement::kOneCue;
  result->cues.pinned_profile_strength =
      result->cues.focus.scale / linear.scale;
  result->scale = combined.scale;
  result->scale_ci_low = combined.ci_low;
  result->scale_ci_high = combined.ci_high;
  result->cues.source = combined.source;
  result->cues.combination = combined.how;
  s << "the scale comes from " << combined.source << ": " << combined.how
    << "; the recorded focus pins the profile's strength at "
    << std::setprecision(2) << result->cues.pinned_profile_strength
    << " x the one used";
  result->psf.status += (result->psf.status.empty() ? "" : "; ") + s.str();
  return true;
}

void DPScaleEstimator::CheckAgainstRecordedFocus(DPScaleResult* result) const {
  // The fitted focal plane g' is where the disparity changes sign, whatever
  // the DP profile; a recorded focus distance (converted to the thin lens's
  // object distance) then gives the scale without any PSF.
  std::vector<double> scales;
  result->cues.focus_scale = kNaN;
  for (size_t i = 0; i < result->views.size(); ++i) {
    DPViewResult& out = result->views[i];
    const DPLensData& lens = views_[i]->lens;
    out.focus_scale = kNaN;
    if (!out.used || !std::isfinite(lens.recorded_focus_mm) ||
        !(out.focus_distance_model > 0)) {
      continue;
    }
    try {
      out.focus_scale =
          FocusObjectDistanceMm(lens.recorded_focus_mm, lens.focal_length_mm) /
          1000 / out.focus_distance_model;
      scales.push_back(out.focus_scale);
    } catch (const std::invalid_argument&) {
      // A recorded focus nearer than the lens can focus: no evidence.
    }
  }
  if (scales.empty()) return;
  result->cues.focus_scale = Percentile(scales, 0.5);
  result->cues.focus_scale_ratio =
      result->cues.dp.scale / result->cues.focus_scale;
  std::ostringstream s;
  s << std::setprecision(4) << "the recorded focus distances of "
    << scales.size() << " used view(s) give a scale of "
    << result->cues.focus_scale;
  if (result->cues.focus.valid) {
    s << " in [" << result->cues.focus.ci_low << ", "
      << result->cues.focus.ci_high << "] (profile-free)";
  }
  if (result->cues.dp.valid) {
    s << "; the DP data alone give " << result->cues.dp.scale << " in ["
      << result->cues.dp.ci_low << ", " << result->cues.dp.ci_high << "], "
      << std::showpos << std::fixed << std::setprecision(1)
      << 100 * (result->cues.focus_scale_ratio - 1) << std::noshowpos
      << " % off it";
    result->cues.focus_agrees =
        result->cues.focus.valid &&
        CombineScaleCues(result->cues.dp, result->cues.focus).agreement ==
            CueAgreement::kAgree;
    if (result->cues.focus_agrees) {
      s << ": they agree (core/scale/scale_cues.h)";
    } else {
      s << ": they DISAGREE (core/scale/scale_cues.h); a DP profile "
        << std::setprecision(2) << result->cues.focus_scale_ratio
        << " x as strong as the one used would reconcile them";
    }
  } else {
    result->cues.focus_agrees = true;
    s << "; the DP data alone leave the scale open";
  }
  // How the answer was formed follows in the COLMAP layer's words
  // (colmap/report/refusal_text: FocusCheckText).
  result->cues.focus_check = s.str();
}

}  // namespace dpsfm
