#include "dpsfm/core/calibration/target_calibration.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <random>
#include <sstream>

#include "dpsfm/core/calibration/target_solver.h"
#include "dpsfm/core/util/check.h"
#include "dpsfm/core/util/curve_math.h"
#include "dpsfm/core/util/statistics.h"

namespace dpsfm {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// All patches in one list; capture and cell of each.
struct PatchList {
  std::vector<const ProfilePatch*> patches;
  std::vector<int> capture_of, cell_of;
};

PatchList CollectPatches(const std::vector<CalibrationCapture>& captures,
                         const DPPsfLayout& layout) {
  PatchList list;
  const int num_captures = static_cast<int>(captures.size());
  for (int i = 0; i < num_captures; ++i) {
    const CalibrationCapture& c = captures[i];
    DPSFM_CHECK(c.lens.Check() && c.working_pitch_mm > 0 &&
                c.target_distance_mm > 0)
        << "capture " << c.name << ": invalid lens data or distance";
    for (const ProfilePatch& p : c.patches) {
      list.patches.push_back(&p);
      list.capture_of.push_back(i);
      list.cell_of.push_back(layout.CellAt(p.x_fraction, p.y_fraction));
    }
  }
  return list;
}

void CheckCropsOfOneSize(const std::vector<const ProfilePatch*>& patches) {
  const cv::Size size = patches[0]->left.size();
  for (const ProfilePatch* p : patches) {
    DPSFM_CHECK(p->left.type() == CV_32FC1 && p->left.size() == size &&
                p->right.size() == size)
        << "calibration patches must be CV_32FC1 crops of one size";
  }
}

// Per capture: name, median reading, predicted radius at the focus used
// and centroid offset. Returns how many captures show visible blur.
int RecordCaptures(const std::vector<CalibrationCapture>& captures,
                   const std::vector<double>& reading_px,
                   const TargetSolution& best,
                   double min_reading_px,
                   TargetCalibration* out) {
  int num_blurred = 0;
  for (size_t i = 0; i < captures.size(); ++i) {
    const CalibrationCapture& c = captures[i];
    out->capture_names.push_back(c.name);
    out->capture_reading_px.push_back(reading_px[i]);
    const double focus = std::isfinite(c.focus_distance_mm)
                             ? c.focus_distance_mm
                             : best.focus_mm;
    out->capture_radius_px.push_back(
        std::isfinite(focus) ? PredictedRadiusPx(c, focus) : kNaN);
    out->capture_centroid_offset.push_back(
        best.capture_kappa.empty() ? kNaN : best.capture_kappa[i]);
    num_blurred += std::isfinite(reading_px[i]) &&
                           std::abs(reading_px[i]) >= min_reading_px
                       ? 1
                       : 0;
  }
  return num_blurred;
}

// Why the captures determine no solution; empty when they do.
std::string WhyNoSolution(int num_blurred,
                          int num_captures,
                          bool focus_unknown,
                          const TargetSolution& best,
                          const TargetCalibrationOptions& options) {
  std::ostringstream s;
  if (num_blurred == 0) {
    s << "none of the " << num_captures
      << " captures shows visible blur (median reading under the linear "
         "split below "
      << options.min_reading_px
      << " px): the target was too close to the "
         "focus or the aperture too small";
  } else if (focus_unknown && num_blurred < 2) {
    s << "with the focus distance unknown the profile needs two or more "
         "captures with visible blur at different distances; "
      << num_blurred << " of " << num_captures
      << " have blur (median reading >= " << options.min_reading_px
      << " px). Give focus_distance_m, or capture the target nearer and "
         "farther than the focus";
  } else if (!std::isfinite(best.kappa)) {
    s << "no profile with a centroid offset in [" << options.min_centroid_offset
      << ", " << options.max_centroid_offset
      << "] R makes every capture's blur agree with its distance"
      << (focus_unknown ? " at any focus distance" : "")
      << " (check the distances, the focus, the lens data and the left/right "
         "order of the views)";
  }
  return s.str();
}

// The solutions of bootstrap resamples of the patches within each capture.
struct BootstrapSamples {
  std::vector<double> focus, kappa, strength;
  std::vector<std::vector<double>> cells;
};

BootstrapSamples ResampleSolutions(const TargetSolver& solver,
                                   const std::vector<std::vector<int>>& all,
                                   int num_cells,
                                   const TargetCalibrationOptions& options) {
  BootstrapSamples samples;
  samples.cells.resize(num_cells);
  if (options.num_bootstrap > 0) {
    const int num_captures = static_cast<int>(all.size());
    std::mt19937_64 rng(options.seed);
    for (int b = 0; b < options.num_bootstrap; ++b) {
      std::vector<std::vector<int>> members(num_captures);
      for (int i = 0; i < num_captures; ++i) {
        if (all[i].empty()) continue;
        std::uniform_int_distribution<size_t> pick(0, all[i].size() - 1);
        for (size_t k = 0; k < all[i].size(); ++k) {
          members[i].push_back(all[i][pick(rng)]);
        }
      }
      const TargetSolution s = solver.Solve(members, nullptr);
      // A resample without a solution counts at the range's ends (it
      // widens the interval rather than vanishing from it).
      samples.kappa.push_back(std::isfinite(s.kappa) ? s.kappa : kNaN);
      samples.strength.push_back(std::isfinite(s.kappa) ? s.strength : kNaN);
      if (solver.FocusUnknown()) samples.focus.push_back(s.focus_mm);
      for (int c = 0; c < num_cells; ++c) {
        if (!s.cell_kappa.empty()) samples.cells[c].push_back(s.cell_kappa[c]);
      }
    }
  }
  return samples;
}

// The 95 % interval of bootstrap values `v` around `value`: NaN without
// resamples, [0, inf] when more than 5 % of them found no solution.
void BootstrapInterval(std::vector<double> v,
                       double value,
                       double* lo,
                       double* hi) {
  const size_t total = v.size();
  v.erase(std::remove_if(
              v.begin(), v.end(), [](double x) { return !std::isfinite(x); }),
          v.end());
  if (total == 0) {
    *lo = *hi = kNaN;
    return;
  }
  if (v.size() < 0.95 * total) {
    *lo = 0;
    *hi = std::numeric_limits<double>::infinity();
    return;
  }
  *lo = std::min(value, Percentile(v, 0.025));
  *hi = std::max(value, Percentile(v, 0.975));
}

// The whole frame's centroid offset, strength and focus with their
// intervals.
void SetWholeFrame(const TargetSolution& best,
                   const BootstrapSamples& samples,
                   bool focus_unknown,
                   TargetCalibration* out) {
  BootstrapInterval(samples.kappa,
                    out->centroid_offset,
                    &out->centroid_offset_ci_low,
                    &out->centroid_offset_ci_high);
  out->strength = best.strength;
  BootstrapInterval(samples.strength,
                    out->strength,
                    &out->strength_ci_low,
                    &out->strength_ci_high);
  if (focus_unknown) {
    BootstrapInterval(samples.focus,
                      out->focus_distance_mm,
                      &out->focus_ci_low_mm,
                      &out->focus_ci_high_mm);
  } else {
    out->focus_ci_low_mm = out->focus_ci_high_mm = out->focus_distance_mm;
  }
}

// Per cell: patches, and its own centroid offset with its interval, or
// the whole frame's.
void SetCells(const TargetSolution& best,
              const BootstrapSamples& samples,
              const std::vector<int>& cell_of,
              TargetCalibration* out) {
  const int n = static_cast<int>(cell_of.size());
  for (int c = 0; c < out->layout.NumCells(); ++c) {
    int count = 0;
    for (int p = 0; p < n; ++p) count += cell_of[p] == c ? 1 : 0;
    out->cell_patches.push_back(count);
    const bool own = std::isfinite(best.cell_kappa[c]);
    out->cell_own.push_back(own);
    out->cell_centroid_offsets.push_back(own ? best.cell_kappa[c]
                                             : out->centroid_offset);
    double lo = out->centroid_offset_ci_low, hi = out->centroid_offset_ci_high;
    if (own) BootstrapInterval(samples.cells[c], best.cell_kappa[c], &lo, &hi);
    out->cell_ci_low.push_back(lo);
    out->cell_ci_high.push_back(hi);
  }
}

double RelativeSide(double value, double lo, double hi) {
  return std::max(value - lo, hi - value) / value;
}

// The profile used is the cells' (the whole frame's where a cell has too
// few patches). The overall strength is what the scale inherits, so it
// must be determined to the limit; a cell only reads its own patches,
// which a scene spreads over all cells, so a cell may be up to twice as
// uncertain (linear light leaves the darker cells of 8-bit captures
// noisier: the R6 II planes' edge cells are 11 % uncertain there, 6 % as
// encoded). (The whole frame's own interval is wide when the profile
// changes across the frame, its patches then being a mixture.)
double WorstCellUncertainty(const TargetCalibration& out, int num_bootstrap) {
  double worst_cell = 0;
  bool any_own = false;
  for (int c = 0; c < out.layout.NumCells(); ++c) {
    if (!out.cell_own[c]) continue;
    any_own = true;
    worst_cell = std::max(worst_cell,
                          RelativeSide(out.cell_centroid_offsets[c],
                                       out.cell_ci_low[c],
                                       out.cell_ci_high[c]));
  }
  if (!any_own || num_bootstrap == 0) {
    worst_cell = RelativeSide(out.centroid_offset,
                              out.centroid_offset_ci_low,
                              out.centroid_offset_ci_high);
  }
  return worst_cell;
}

std::string Summary(const TargetCalibration& out, bool focus_unknown) {
  std::ostringstream s;
  s << std::setprecision(4) << "centroid offset " << out.centroid_offset
    << " R (95 % interval " << out.centroid_offset_ci_low << " - "
    << out.centroid_offset_ci_high << "; translating disk "
    << TranslatingDiskPsf::CentroidOffsetPerRadius() << " R)";
  if (focus_unknown) {
    s << ", focus fitted at " << out.focus_distance_mm / 1000 << " m from the "
      << "sensor (95 % interval " << out.focus_ci_low_mm / 1000 << " - "
      << out.focus_ci_high_mm / 1000 << " m)";
  }
  if (std::isfinite(out.near_centroid_offset) &&
      std::isfinite(out.far_centroid_offset)) {
    s << "; nearer than the focus " << out.near_centroid_offset
      << " R, farther " << out.far_centroid_offset << " R";
  }
  s << "; strength " << out.strength << " R (95 % interval "
    << out.strength_ci_low << " - " << out.strength_ci_high << ")";
  s << "; per cell of the " << out.layout.ToString() << ":";
  for (int c = 0; c < out.layout.NumCells(); ++c) {
    s << " " << out.cell_centroid_offsets[c] << " [" << out.cell_ci_low[c]
      << ", " << out.cell_ci_high[c] << "]" << (out.cell_own[c] ? "" : "*");
  }
  return s.str();
}

// Why the intervals leave the calibration undetermined; empty when they do
// not.
std::string WhyUndetermined(double strength_side,
                            double worst_cell,
                            const TargetCalibrationOptions& options) {
  // As a fraction of the limit: the strength's side against 1 x, the worst
  // cell's against 2 x.
  double worst_side = std::isfinite(strength_side)
                          ? std::max(worst_cell / 2, strength_side)
                          : std::numeric_limits<double>::infinity();
  if (options.num_bootstrap == 0) worst_side = kNaN;
  if (worst_side <= options.max_relative_uncertainty) return "";
  const bool strength_worse = !(strength_side <= worst_cell / 2);
  std::ostringstream s;
  s << ": not determined ("
    << (strength_worse ? "the strength" : "a cell's centroid offset")
    << " is uncertain by "
    << (std::isfinite(worst_side)
            ? std::to_string(std::lround(
                  100 * (strength_worse ? strength_side : worst_cell))) +
                  " %"
            : std::string("an unbounded amount"))
    << ", limit "
    << std::lround(100 * options.max_relative_uncertainty *
                   (strength_worse ? 1 : 2))
    << " %)";
  return s.str();
}

}  // namespace

bool TargetCalibrationOptions::Check(std::string* failure) const {
  DPSFM_CHECK_NESTED_OPTIONS(blur);
  if (!SplitProfileParams::CheckCentroidOffsetRange(
          min_centroid_offset, max_centroid_offset, failure)) {
    return false;
  }
  DPSFM_CHECK_OPTION_VALUE(node_ratio > 1.01 && node_ratio < 2, node_ratio);
  DPSFM_CHECK_OPTION_GE(min_reading_px, 0);
  DPSFM_CHECK_OPTION_GE(min_patches, 3);
  DPSFM_CHECK_OPTION_GE(grid_rows, 1);
  DPSFM_CHECK_OPTION_GE(grid_cols, 1);
  DPSFM_CHECK_OPTION_GT(min_focus_mm, 0);
  DPSFM_CHECK_OPTION_GT(max_focus_mm, min_focus_mm);
  DPSFM_CHECK_OPTION_GE(num_focus_steps, 10);
  DPSFM_CHECK_OPTION_GT(max_relative_uncertainty, 0);
  DPSFM_CHECK_OPTION_GE(num_bootstrap, 0);
  DPSFM_CHECK_OPTION_VALUE(num_threads == -1 || num_threads > 0, num_threads);
  return true;
}

TargetCalibration CalibrateFromTargets(
    const std::vector<CalibrationCapture>& captures,
    const TargetCalibrationOptions& options) {
  DPSFM_CHECK_OPTIONS(options, "TargetCalibrationOptions");
  const auto start = std::chrono::steady_clock::now();
  TargetCalibration out;
  out.layout.rows = options.grid_rows;
  out.layout.cols = options.grid_cols;
  auto finish = [&]() {
    out.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
            .count();
    return out;
  };
  const int num_captures = static_cast<int>(captures.size());
  DPSFM_CHECK_GT(num_captures, 0) << "no calibration captures";

  const PatchList list = CollectPatches(captures, out.layout);
  const int n = static_cast<int>(list.patches.size());
  if (n == 0) {
    out.reason = "no textured patch in any capture";
    return finish();
  }
  CheckCropsOfOneSize(list.patches);

  const std::vector<double> kappas = GeometricNodes(options.min_centroid_offset,
                                                    options.max_centroid_offset,
                                                    options.node_ratio);
  const TargetReadings readings = ReadAlongPath(kappas, list.patches, options);
  const TargetSolver solver(
      captures, options, out.layout, kappas, readings, list.cell_of);
  const bool focus_unknown = solver.FocusUnknown();

  std::vector<std::vector<int>> all(num_captures);
  for (int p = 0; p < n; ++p) all[list.capture_of[p]].push_back(p);
  std::vector<double> reading_px(num_captures, kNaN);
  const TargetSolution best = solver.Solve(all, &reading_px);
  out.focus_fitted = focus_unknown;
  const int num_blurred =
      RecordCaptures(captures, reading_px, best, options.min_reading_px, &out);
  out.reason =
      WhyNoSolution(num_blurred, num_captures, focus_unknown, best, options);
  if (!out.reason.empty()) return finish();
  // Given: the first capture's (each capture used its own).
  out.focus_distance_mm =
      focus_unknown ? best.focus_mm : captures[0].focus_distance_mm;
  out.centroid_offset = best.kappa;
  out.near_centroid_offset = best.near_kappa;
  out.far_centroid_offset = best.far_kappa;

  const BootstrapSamples samples =
      ResampleSolutions(solver, all, out.layout.NumCells(), options);
  SetWholeFrame(best, samples, focus_unknown, &out);
  SetCells(best, samples, list.cell_of, &out);

  out.worst_cell_uncertainty = WorstCellUncertainty(out, options.num_bootstrap);
  const double strength_side =
      RelativeSide(out.strength, out.strength_ci_low, out.strength_ci_high);
  const std::string undetermined =
      WhyUndetermined(strength_side, out.worst_cell_uncertainty, options);
  out.determined = undetermined.empty();
  out.reason = Summary(out, focus_unknown) + undetermined;
  return finish();
}

}  // namespace dpsfm
