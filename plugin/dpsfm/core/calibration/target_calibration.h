// Calibrating a camera's DP profile from captures a shop can make: a
// textured plane, fronto-parallel, shot at two or more distances, with the
// focus distance given or unknown.
//
// What the captures determine: the blur search reads a patch's radius
// under an assumed profile, and the reading scales inversely with the
// profile's strength (its centroid offset per radius, kappa). Each
// capture's patches are searched once along the family's path by kappa
// (SplitProfileParams::ForCentroidOffset); the median reading per capture
// (and per region of the frame) against kappa is a curve, and the capture's
// kappa is where that curve meets the radius the thin lens predicts for the
// target. With the focus unknown, the focus is the one at which every
// capture agrees on kappa (two captures at different distances fix it:
// the signs and the ratio of their disparities are profile-free). A
// bootstrap over patches gives the intervals of kappa and of the focus.
//
// The profile changes across the frame on real sensors (the Canon R6 II's
// disparity falls by about half towards the left and right edges), so
// kappa is fitted per cell of a grid as well, with the focus shared.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/calibration/psf_calibration.h"
#include "dpsfm/core/optics/dp_psf.h"
#include "dpsfm/core/optics/lens_model.h"

namespace dpsfm {

struct CalibrationCapture {
  std::string name;
  // Grey crops (ExtractProfilePatches) with their position in the frame.
  std::vector<ProfilePatch> patches;
  DPLensData lens;
  double working_pitch_mm = 0;  // pitch of the crops' pixels
  // From the camera's focal-plane mark (the sensor plane), in mm.
  double target_distance_mm = 0;
  // NaN = unknown (fitted, shared by every capture that leaves it unknown).
  double focus_distance_mm = std::numeric_limits<double>::quiet_NaN();
  // Where the lens's entrance pupil (the no-parallax point; the origin of
  // SfM depths) lies in front of the focal-plane mark at this focus, in mm;
  // 0 = unknown: the thin lens's position (PredictedRadiusPx).
  double entrance_pupil_mm = 0;
};

struct TargetCalibrationOptions {
  // The blur search (max_radius_px must match the crops' border).
  BlurEstimationOptions blur;
  // kappa nodes: min, min q, min q^2, ... up to max (GeometricNodes; q is
  // the spacing of 17 nodes over 0.03-0.414 R, the family's range before
  // its bright rim).
  double min_centroid_offset = 0.03;
  double max_centroid_offset = 0.47;
  double node_ratio = 1.1783;
  // A capture whose patches read less than this (median |r| under the
  // linear split) carries too little blur to see the profile: sharp
  // captures read 0.5-0.7 px of noise (real f/20 planes: 0.52 px).
  double min_reading_px = 0.7;
  // A median needs this many valid patch readings.
  int min_patches = 12;
  // Grid of regions (the whole frame is fitted too).
  int grid_rows = 2;
  int grid_cols = 3;
  // Focus search range (sensor distance, mm), inverse-distance grid.
  double min_focus_mm = 250;
  double max_focus_mm = 100000;
  int num_focus_steps = 4000;
  // The calibration is refused when the 95 % interval of the overall
  // strength is wider than this fraction of it (each side), or a cell's
  // centroid offset's than twice this.
  double max_relative_uncertainty = 0.1;
  int num_bootstrap = 200;
  int num_threads = -1;
  uint64_t seed = 42;
  bool Check(std::string* failure = nullptr) const;
};

struct TargetCalibration {
  bool determined = false;
  // The largest relative (95 %, one side) uncertainty of a cell's centroid
  // offset (of the whole frame's when no cell has its own).
  double worst_cell_uncertainty = 0;
  std::string reason;  // why not, or a summary
  // The focus (sensor distance, mm) used: given, or fitted with its 95 %
  // interval.
  bool focus_fitted = false;
  double focus_distance_mm = 0;
  double focus_ci_low_mm = 0, focus_ci_high_mm = 0;
  // Whole frame.
  double centroid_offset = 0;
  double centroid_offset_ci_low = 0, centroid_offset_ci_high = 0;
  // Per cell of `layout` (row-major); cells with too few patches take the
  // whole frame's value (cell_own false).
  DPPsfLayout layout;
  std::vector<double> cell_centroid_offsets;
  std::vector<double> cell_ci_low, cell_ci_high;
  std::vector<int> cell_patches;
  std::vector<bool> cell_own;
  // The profile's overall strength: the patch-weighted geometric mean of
  // the cells' centroid offsets, and its 95 % interval (the bootstrap
  // moves every cell together through the shared focus, so this, not the
  // worst cell's interval, is what the scale inherits).
  double strength = 0;
  double strength_ci_low = 0, strength_ci_high = 0;
  // Per capture: predicted radius (px) at the focus used, median reading
  // under the linear split, and the capture's own kappa (NaN if it has too
  // little blur); nearer and farther than the focus separately when both
  // occur (real lenses' defocus can differ between the two sides).
  std::vector<std::string> capture_names;
  std::vector<double> capture_radius_px, capture_reading_px,
      capture_centroid_offset;
  double near_centroid_offset = std::numeric_limits<double>::quiet_NaN();
  double far_centroid_offset = std::numeric_limits<double>::quiet_NaN();
  double seconds = 0;
};

TargetCalibration CalibrateFromTargets(
    const std::vector<CalibrationCapture>& captures,
    const TargetCalibrationOptions& options);

}  // namespace dpsfm
