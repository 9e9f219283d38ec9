#include "dpsfm/core/calibration/target_solver.h"

#include <algorithm>
#include <cmath>

#include "dpsfm/core/util/statistics.h"

namespace dpsfm {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Median reading per node over `members` (patch indices, with
// multiplicity); NaN where fewer than min_patches are valid.
std::vector<double> MedianCurve(const TargetReadings& readings,
                                const std::vector<int>& members,
                                int min_patches) {
  std::vector<double> curve(readings.size(), kNaN);
  std::vector<double> values;
  for (size_t k = 0; k < readings.size(); ++k) {
    values.clear();
    for (int p : members) {
      if (std::isfinite(readings[k][p])) values.push_back(readings[k][p]);
    }
    if (static_cast<int>(values.size()) >= min_patches) {
      curve[k] = Percentile(values, 0.5);
    }
  }
  return curve;
}

// The kappa at which a capture's median reading equals the predicted
// radius: readings shrink as the assumed kappa grows (log-log
// interpolation between nodes). NaN when the signs disagree or the radius
// lies outside the readings' range.
double KappaForRadius(const std::vector<double>& kappas,
                      const std::vector<double>& curve,
                      double radius) {
  for (size_t k = 0; k + 1 < kappas.size(); ++k) {
    const double a = curve[k], b = curve[k + 1];
    if (!std::isfinite(a) || !std::isfinite(b)) continue;
    if (a * radius <= 0 || b * radius <= 0) continue;
    const double la = std::log(std::abs(a)), lb = std::log(std::abs(b));
    const double lr = std::log(std::abs(radius));
    if ((la - lr) * (lb - lr) > 0) continue;
    const double t = la == lb ? 0.5 : (la - lr) / (la - lb);
    return std::exp(std::log(kappas[k]) +
                    t * (std::log(kappas[k + 1]) - std::log(kappas[k])));
  }
  return kNaN;
}

double GeometricMean(const std::vector<double>& v) {
  double sum = 0;
  int n = 0;
  for (const double x : v) {
    if (std::isfinite(x) && x > 0) {
      sum += std::log(x);
      ++n;
    }
  }
  return n > 0 ? std::exp(sum / n) : kNaN;
}

// The linear split's node, for the "enough blur" test.
size_t LinearSplitNode(const std::vector<double>& kappas) {
  const double linear = SplitProfileParams().CentroidOffset();
  size_t linear_node = 0;
  for (size_t k = 0; k < kappas.size(); ++k) {
    if (std::abs(std::log(kappas[k] / linear)) <
        std::abs(std::log(kappas[linear_node] / linear))) {
      linear_node = k;
    }
  }
  return linear_node;
}

// The focus candidates (sensor distance, mm), evenly spaced in inverse
// distance over the options' range.
std::vector<double> FocusGrid(const TargetCalibrationOptions& options) {
  std::vector<double> focus_grid;
  const double a = 1 / options.max_focus_mm, b = 1 / options.min_focus_mm;
  for (int k = 0; k < options.num_focus_steps; ++k) {
    focus_grid.push_back(1 /
                         (a + (b - a) * (k + 0.5) / options.num_focus_steps));
  }
  return focus_grid;
}

}  // namespace

TargetReadings ReadAlongPath(const std::vector<double>& kappas,
                             const std::vector<const ProfilePatch*>& patches,
                             const TargetCalibrationOptions& options) {
  const int n = static_cast<int>(patches.size());
  TargetReadings readings(kappas.size(), std::vector<double>(n, kNaN));
  std::vector<PreparedBlurPatch> prepared;  // by the first profile's search
  for (size_t k = 0; k < kappas.size(); ++k) {
    const std::vector<PatchBlurEstimate> estimates = EstimateProfilePatches(
        SplitProfilePsf(SplitProfileParams::ForCentroidOffset(kappas[k])),
        options.blur,
        patches,
        options.num_threads,
        &prepared);
    // A patch reads at every profile of the path where its minimum lies
    // inside the bound, determined by the noise or not: the curve is how
    // one patch's reading moves with the profile, and a patch dropped at
    // some profiles and kept at others would make each profile's median
    // one of a different set (with a wrong f-number the captures' curves
    // then never met, and the fit refused as undetermined). The planes'
    // patches are textured (CalibrationRunOptions' texture screening).
    for (int p = 0; p < n; ++p) {
      const PatchBlurEstimate& e = estimates[p];
      const bool read = e.valid || (e.reject_reason == kBlurUndetermined &&
                                    !e.at_bound);
      if (read && std::isfinite(e.radius_px)) readings[k][p] = e.radius_px;
    }
  }
  return readings;
}

double PredictedRadiusPx(const CalibrationCapture& c, double focus_mm) {
  const double f = c.lens.focal_length_mm;
  // Object distances as the scenes' depths will be: from the entrance
  // pupil when it is known, else from the thin lens focused at focus_mm.
  const bool pupil = c.entrance_pupil_mm > 0;
  const double u_g = pupil ? focus_mm - c.entrance_pupil_mm
                           : FocusObjectDistanceMm(focus_mm, f);
  const double u_t =
      pupil ? c.target_distance_mm - c.entrance_pupil_mm
            : ObjectDistanceFromSensorMm(c.target_distance_mm, focus_mm, f);
  if (!(u_g > f)) return std::numeric_limits<double>::quiet_NaN();
  return BlurRadiusPxFromDiameterMm(SignedBlurDiameterMm(c.lens, u_g, u_t),
                                    c.working_pitch_mm);
}

// Each capture's median curve along the path, and whether it shows
// visible blur.
struct TargetSolver::CaptureCurves {
  std::vector<std::vector<double>> curves;
  std::vector<bool> blurred;
  int num_blurred = 0;
};

TargetSolver::TargetSolver(const std::vector<CalibrationCapture>& captures,
                           const TargetCalibrationOptions& options,
                           const DPPsfLayout& layout,
                           const std::vector<double>& kappas,
                           const TargetReadings& readings,
                           const std::vector<int>& cell_of)
    : captures_(captures),
      options_(options),
      num_captures_(static_cast<int>(captures.size())),
      num_cells_(layout.NumCells()),
      kappas_(kappas),
      readings_(readings),
      cell_of_(cell_of),
      linear_node_(LinearSplitNode(kappas)) {
  for (const CalibrationCapture& c : captures) {
    focus_unknown_ = focus_unknown_ || !std::isfinite(c.focus_distance_mm);
  }
  if (focus_unknown_) focus_grid_ = FocusGrid(options);
  cell_weight_.assign(num_cells_, 0);
  for (size_t p = 0; p < cell_of.size(); ++p) cell_weight_[cell_of[p]] += 1;
}

TargetSolution TargetSolver::Solve(const std::vector<std::vector<int>>& members,
                                   std::vector<double>* readings_px) const {
  TargetSolution s;
  const CaptureCurves curves = MedianCurves(members, readings_px);
  const double focus = SharedFocus(curves);
  if (!std::isfinite(focus)) return s;
  s.focus_mm = focus;
  s.capture_kappa = KappasAt(curves, focus);
  s.kappa = GeometricMean(s.capture_kappa);
  SplitNearAndFar(focus, &s);
  s.cell_kappa = CellKappas(members, curves, focus);
  s.strength = Strength(s);
  return s;
}

TargetSolver::CaptureCurves TargetSolver::MedianCurves(
    const std::vector<std::vector<int>>& members,
    std::vector<double>* readings_px) const {
  CaptureCurves c;
  c.curves.resize(num_captures_);
  c.blurred.assign(num_captures_, false);
  for (int i = 0; i < num_captures_; ++i) {
    c.curves[i] = MedianCurve(readings_, members[i], options_.min_patches);
    const double r = c.curves[i][linear_node_];
    if (readings_px) (*readings_px)[i] = r;
    c.blurred[i] = std::isfinite(r) && std::abs(r) >= options_.min_reading_px;
    c.num_blurred += c.blurred[i] ? 1 : 0;
  }
  return c;
}

double TargetSolver::FocusOf(int i, double candidate) const {
  return std::isfinite(captures_[i].focus_distance_mm)
             ? captures_[i].focus_distance_mm
             : candidate;
}

std::vector<double> TargetSolver::KappasAt(const CaptureCurves& c,
                                           double candidate) const {
  std::vector<double> k(num_captures_, kNaN);
  for (int i = 0; i < num_captures_; ++i) {
    if (!c.blurred[i]) continue;
    const double f = FocusOf(i, candidate);
    if (f < 4 * captures_[i].lens.focal_length_mm) continue;
    k[i] = KappaForRadius(
        kappas_, c.curves[i], PredictedRadiusPx(captures_[i], f));
  }
  return k;
}

// The focus the captures that leave it unknown share (0 when every capture
// gives its own); NaN when no candidate fits.
double TargetSolver::SharedFocus(const CaptureCurves& c) const {
  double focus = kNaN;
  if (!focus_unknown_) {
    focus = 0;  // each capture's own
  } else if (c.num_blurred >= 2) {
    // The focus at which the most captures find a centroid offset (a
    // capture whose blur the family cannot reach at a candidate, e.g.
    // beyond the search bound, leaves it), and among those the one where
    // they agree best.
    const int needed = std::max(2, (c.num_blurred + 1) / 2);
    double best = std::numeric_limits<double>::infinity();
    int best_count = 0;
    for (const double candidate : focus_grid_) {
      const std::vector<double> k = KappasAt(c, candidate);
      double sum = 0, sum2 = 0;
      int m = 0;
      for (int i = 0; i < num_captures_; ++i) {
        if (!c.blurred[i] || !std::isfinite(k[i])) continue;
        sum += std::log(k[i]);
        sum2 += std::log(k[i]) * std::log(k[i]);
        ++m;
      }
      if (m < needed) continue;
      const double variance = sum2 / m - (sum / m) * (sum / m);
      if (m > best_count || (m == best_count && variance < best)) {
        best_count = m;
        best = variance;
        focus = candidate;
      }
    }
  }
  return focus;
}

// The captures' centroid offsets nearer and farther than the focus.
void TargetSolver::SplitNearAndFar(double focus, TargetSolution* s) const {
  std::vector<double> near, far;
  for (int i = 0; i < num_captures_; ++i) {
    if (!std::isfinite(s->capture_kappa[i])) continue;
    (PredictedRadiusPx(captures_[i], FocusOf(i, focus)) < 0 ? near : far)
        .push_back(s->capture_kappa[i]);
  }
  s->near_kappa = GeometricMean(near);
  s->far_kappa = GeometricMean(far);
}

// Cells: the same focus, each capture's patches in the cell.
std::vector<double> TargetSolver::CellKappas(
    const std::vector<std::vector<int>>& members,
    const CaptureCurves& curves,
    double focus) const {
  std::vector<double> cell_kappa(num_cells_, kNaN);
  for (int c = 0; c < num_cells_; ++c) {
    std::vector<double> k;
    for (int i = 0; i < num_captures_; ++i) {
      if (!curves.blurred[i]) continue;
      std::vector<int> in_cell;
      for (int p : members[i]) {
        if (cell_of_[p] == c) in_cell.push_back(p);
      }
      const std::vector<double> curve =
          MedianCurve(readings_, in_cell, options_.min_patches);
      k.push_back(KappaForRadius(
          kappas_, curve, PredictedRadiusPx(captures_[i], FocusOf(i, focus))));
    }
    cell_kappa[c] = GeometricMean(k);
  }
  return cell_kappa;
}

double TargetSolver::Strength(const TargetSolution& s) const {
  double log_sum = 0, weight = 0;
  for (int c = 0; c < num_cells_; ++c) {
    const double k = std::isfinite(s.cell_kappa[c]) ? s.cell_kappa[c] : s.kappa;
    log_sum += cell_weight_[c] * std::log(k);
    weight += cell_weight_[c];
  }
  return weight > 0 ? std::exp(log_sum / weight) : s.kappa;
}

}  // namespace dpsfm
