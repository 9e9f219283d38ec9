// The private data of DPScaleEstimator that its implementation files share
// (scale_estimator.cc, profile_self_calibration.cc, scale_stages.cc). Not
// for other users.
#pragma once

#include <cmath>
#include <vector>

#include "dpsfm/core/blur/crop_store.h"
#include "dpsfm/core/scale/scale_estimator.h"

namespace dpsfm {

// What AddView keeps of a view.
struct DPScaleEstimator::ViewData {
  DPViewSummary summary;
  DPLensData lens;
  double working_pitch_mm = 0;
  std::vector<PatchSample> samples;  // valid patches only
  std::vector<StoredCrop> stored;    // best selected patches (crop_store.h)
};

// The terms that widen a statistical scale interval: the estimator's
// systematic term and the lens geometry's (relative, in quadrature), then
// the DP profile's own uncertainty (factors on the bounds).
struct DPScaleEstimator::IntervalTerms {
  double systematic = 0;
  double lens_geometry = 0;
  double profile_low = 1, profile_high = 1;

  void Widen(double s, double* lo, double* hi) const {
    const double sys = std::hypot(systematic, lens_geometry) * s;
    const double dl = std::max(0.0, s - *lo), dh = std::max(0.0, *hi - s);
    *lo = s - std::sqrt(dl * dl + sys * sys);
    *hi = s + std::sqrt(dh * dh + sys * sys);
  }
  void ApplyProfile(double* lo, double* hi) const {
    *lo *= profile_low;
    *hi *= profile_high;
  }
};

// The linear stage's interval widened by the systematic terms but not yet
// by the profile's, and its relative width before either: LinearRefusal
// tells by them whether the profile or the data leave the scale open.
struct DPScaleEstimator::StatisticalInterval {
  double width = 0;  // the bootstrap's, relative to the scale
  double ci_low = 0, ci_high = 0;
};

}  // namespace dpsfm
