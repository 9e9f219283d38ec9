// The calibration targets file of dp_psf_calibrator (targets.csv).
#pragma once

#include <string>
#include <vector>

#include "dpsfm/core/optics/lens_model.h"

namespace dpsfm {

// One row of a calibration targets file (dp_psf_calibrator): a DP capture
// of a planar, fronto-parallel textured target.
struct CalibrationTarget {
  std::string name;  // DP view file name (as under left/)
  // From the camera's focal-plane mark (the sensor plane); the calibration
  // turns them into the thin lens's object distances.
  double target_distance_m = 0;
  double focus_distance_m = 0;  // NaN = unknown (an empty cell): fitted
  DPLensData lens;              // pitch: of the DP frame's pixels
  int line = 0;                 // in targets.csv, for messages
  // The capture's DP view files, relative to the captures folder; empty:
  // left/<name> with right/<name> (or sum/<name>).
  std::string left, right;
};

// A CSV whose header names its columns (text.h, CsvTable): name,
// target_distance_m, focal_length_mm, f_number and pixel_pitch_um required;
// focus_distance_m (empty cells: fitted) and left, right (both or neither)
// optional. Lengths may carry a unit ("600mm", "60 cm"), converted to the
// column's (logged).
std::vector<CalibrationTarget> ReadCalibrationTargets(const std::string& path);

}  // namespace dpsfm
