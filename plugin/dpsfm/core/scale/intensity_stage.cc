// DPScaleEstimator's intensity stage: the linear scale refined by matching
// the DP views' intensities on the stored crops (intensity_search.h), and
// whether its answer is adopted.
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "dpsfm/core/scale/scale_estimator.h"
#include "dpsfm/core/scale/scale_estimator_data.h"
#include "dpsfm/core/util/check.h"

namespace dpsfm {
namespace {

// Whether `value` lies in [lo, hi] widened by a relative systematic term
// (in quadrature with each half).
bool IntervalContains(
    double centre, double lo, double hi, double relative, double value) {
  const double sys = relative * centre;
  const double dl = std::max(0.0, centre - lo), dh = std::max(0.0, hi - centre);
  return value >= centre - std::sqrt(dl * dl + sys * sys) &&
         value <= centre + std::sqrt(dh * dh + sys * sys);
}

// Whether the intensity search's answer is adopted (*adopt) and the status
// saying why (not): it must lie inside the searched range, have an interval
// narrow enough and a minimum stable under resampling, and agree with the
// linear estimate within its own interval plus the systematic term.
std::string IntensityVerdict(const IntensitySearchResult& intensity,
                             const IntensitySearchOptions& search,
                             const DPScaleOptions& options,
                             double linear_scale,
                             bool* adopt) {
  *adopt = false;
  std::ostringstream status;
  if (!intensity.success) {
    status << "failed (" << intensity.failure_reason
           << "); linear estimate kept";
    return status.str();
  }
  const double width =
      (intensity.scale_ci_high - intensity.scale_ci_low) / intensity.scale;
  if (intensity.at_boundary) {
    status << "loss minimum at the edge of the searched range (s* x (1 +- "
           << search.relative_range
           << ")): the linear and intensity cues disagree; linear "
              "estimate kept";
  } else if (search.num_bootstrap == 0) {
    status << "no bootstrap (num_bootstrap 0), so no interval; linear "
              "estimate kept";
  } else if (width > options.intensity.max_ci_relative_width) {
    status << "loss curve too flat ("
           << std::lround(100 * search.confidence_level) << " % interval "
           << std::fixed << std::setprecision(1) << width * 100
           << " % of the scale); linear estimate kept";
  } else if (intensity.bootstrap_support <
             options.intensity.min_bootstrap_support) {
    status << "minimum not stable under resampling (support "
           << intensity.bootstrap_support << "); linear estimate kept";
  } else if (!IntervalContains(intensity.scale,
                               intensity.scale_ci_low,
                               intensity.scale_ci_high,
                               options.interval.scale_systematic_uncertainty,
                               linear_scale)) {
    // Both stages read the same patches; if they disagree beyond the
    // intensity stage's own interval (plus the systematic term), one of
    // them is wrong and the linear stage is the robust one (L1 over
    // per-patch estimates vs a sum of loss curves that a few patches can
    // pull).
    status << "disagrees with the linear estimate (intensity "
           << intensity.scale << ", interval [" << intensity.scale_ci_low
           << ", " << intensity.scale_ci_high << "] excludes the linear "
           << linear_scale << "); linear estimate kept";
  } else {
    status << "used (moved the scale by " << std::showpos << std::fixed
           << std::setprecision(2) << 100 * (intensity.scale / linear_scale - 1)
           << std::noshowpos << " % from the linear estimate)";
    *adopt = true;
  }
  return status.str();
}

}  // namespace

void DPScaleEstimator::IntensityStage(
    const LinearEstimate& linear,
    const std::vector<std::vector<PatchSample>>& samples,
    const DPPsfField& field,
    const IntervalTerms& terms,
    IntensityStatsCache* cache,
    DPScaleResult* result) const {
  const std::shared_ptr<const DPPsfModel> psf = field.cells[0];
  const bool banded = field.cells.size() > 1;
  result->intensity.loss = IntensityLossName(options_.intensity.search.loss);
  if (result->cues.combined) {
    // The DP data alone left the scale open: the intensity stage reads the
    // same profile, the very thing that is uncertain here.
    result->intensity.status =
        "skipped: the answer combines the DP data with the recorded focus "
        "(the DP data alone are wider than the limit), and this stage would "
        "read the same profile whose uncertainty widened them";
  } else if (!options_.intensity.enabled) {
    result->intensity.status = "disabled; linear estimate kept";
  } else {
    std::vector<IntensityView> iviews;
    std::vector<IntensityPatch> ipatches;
    for (int i : linear.selected_views) {
      const ViewData& v = *views_[i];
      IntensityView iv;
      iv.lens = v.lens;
      iv.pixel_pitch_mm = v.working_pitch_mm;
      iv.focus_distance_model = linear.views[i].focus_model;
      const int index = static_cast<int>(iviews.size());
      iviews.push_back(iv);
      for (const StoredCrop& st : v.stored) {
        IntensityPatch ip;
        ip.view = index;
        if (!samples[i][st.sample].selected) continue;
        ip.depth = samples[i][st.sample].depth;
        if (banded) {
          ip.psf = field.cells[samples[i][st.sample].psf_band].get();
        }
        ip.left = st.left;
        ip.right = st.right;
        ip.border = st.border;
        ipatches.push_back(ip);
      }
    }
    IntensitySearchOptions search = options_.intensity.search;
    search.seed = options_.seed;
    search.num_threads = options_.num_threads;
    // Clamp radii to the blur search's bound of each view (the crops' border
    // supports exactly that).
    double max_r = 0;
    for (int i : linear.selected_views) {
      max_r = std::max(max_r,
                       views_[i]->summary.max_radius_px *
                           (result->psf.self_calibrated
                                ? options_.self_calibration.radius_factor
                                : 1.0));
    }
    search.max_radius_px = max_r;
    IntensitySearchResult intensity;
    try {
      intensity = SearchScaleByIntensity(
          iviews, ipatches, linear.scale, *psf, search, cache);
    } catch (const CheckFailure& e) {
      intensity.success = false;
      intensity.failure_reason = e.what();
    }
    result->intensity.candidate_scales = intensity.candidate_scales;
    result->intensity.candidate_losses = intensity.candidate_losses;
    result->intensity.failed_evaluations = intensity.num_failed_evaluations;
    result->intensity.nodes_reused = intensity.num_nodes_reused;
    result->intensity.nodes_computed = intensity.num_nodes_computed;
    bool adopt = false;
    result->intensity.status =
        IntensityVerdict(intensity, search, options_, linear.scale, &adopt);
    if (intensity.success) {
      result->intensity.scale = intensity.scale;
      result->intensity.ci_low = intensity.scale_ci_low;
      result->intensity.ci_high = intensity.scale_ci_high;
      result->intensity.bootstrap_support = intensity.bootstrap_support;
    }
    if (adopt) {
      result->intensity.used = true;
      result->scale = intensity.scale;
      result->scale_ci_low = intensity.scale_ci_low;
      result->scale_ci_high = intensity.scale_ci_high;
      terms.Widen(result->scale, &result->scale_ci_low, &result->scale_ci_high);
      terms.ApplyProfile(&result->scale_ci_low, &result->scale_ci_high);
      result->num_patches = intensity.num_patches;
    }
  }
}

}  // namespace dpsfm
