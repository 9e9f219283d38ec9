// The solving step of CalibrateFromTargets (target_calibration.h): from
// every patch's reading along the family's path by centroid offset, the
// focus at which the captures agree and the centroid offset (kappa) of
// each capture and cell of the frame, for one set of patches (all of them,
// or a bootstrap resample).
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

#include "dpsfm/core/calibration/target_calibration.h"

namespace dpsfm {

// readings[node][patch]: signed radius read under node's profile (NaN = no
// estimate).
using TargetReadings = std::vector<std::vector<double>>;

// Readings along the path (the expensive part), in parallel: the blur
// search of every patch under the profile of each centroid offset in
// `kappas`.
TargetReadings ReadAlongPath(const std::vector<double>& kappas,
                             const std::vector<const ProfilePatch*>& patches,
                             const TargetCalibrationOptions& options);

// The signed blur radius (px) the thin lens predicts for a capture's target
// with the focus (sensor distance, mm) at focus_mm: object distances from
// the capture's entrance pupil when it is given, else from the thin lens
// (NaN when the focus lies within a focal length of the pupil).
double PredictedRadiusPx(const CalibrationCapture& c, double focus_mm);

// NaN where the captures determine nothing.
struct TargetSolution {
  // 0: every capture's own.
  double focus_mm = std::numeric_limits<double>::quiet_NaN();
  double kappa = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> capture_kappa;
  std::vector<double> cell_kappa;
  // See TargetCalibration::strength.
  double strength = std::numeric_limits<double>::quiet_NaN();
  double near_kappa = std::numeric_limits<double>::quiet_NaN();
  double far_kappa = std::numeric_limits<double>::quiet_NaN();
};

// One solution from patch members (with multiplicity) per capture. Holds
// references to its arguments, which must outlive it.
class TargetSolver {
 public:
  // kappas: the path's nodes; readings: ReadAlongPath's; cell_of: each
  // patch's cell of `layout`.
  TargetSolver(const std::vector<CalibrationCapture>& captures,
               const TargetCalibrationOptions& options,
               const DPPsfLayout& layout,
               const std::vector<double>& kappas,
               const TargetReadings& readings,
               const std::vector<int>& cell_of);

  // True when a capture leaves the focus unknown (it is then fitted).
  bool FocusUnknown() const { return focus_unknown_; }

  // members[capture]: patch indices. readings_px (may be null): each
  // capture's median reading under the linear split.
  TargetSolution Solve(const std::vector<std::vector<int>>& members,
                       std::vector<double>* readings_px) const;

 private:
  struct CaptureCurves;
  CaptureCurves MedianCurves(const std::vector<std::vector<int>>& members,
                             std::vector<double>* readings_px) const;
  double FocusOf(int capture, double candidate) const;
  std::vector<double> KappasAt(const CaptureCurves& curves,
                               double candidate) const;
  double SharedFocus(const CaptureCurves& curves) const;
  void SplitNearAndFar(double focus, TargetSolution* s) const;
  std::vector<double> CellKappas(const std::vector<std::vector<int>>& members,
                                 const CaptureCurves& curves,
                                 double focus) const;
  double Strength(const TargetSolution& s) const;

  const std::vector<CalibrationCapture>& captures_;
  const TargetCalibrationOptions& options_;
  const int num_captures_;
  const int num_cells_;
  const std::vector<double>& kappas_;
  const TargetReadings& readings_;
  const std::vector<int>& cell_of_;
  const size_t linear_node_;
  bool focus_unknown_ = false;
  std::vector<double> focus_grid_;
  std::vector<double> cell_weight_;
};

}  // namespace dpsfm
