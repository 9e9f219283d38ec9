#include "dpsfm/core/calibration/target_calibration.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <random>
#include <sstream>

#include "dpsfm/core/util/check.h"
#include "dpsfm/core/util/curve_math.h"
#include "dpsfm/core/util/statistics.h"

namespace dpsfm {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// readings[node][patch]: signed radius read under node's profile (NaN = no
// estimate).
using Readings = std::vector<std::vector<double>>;

// Median reading per node over `members` (patch indices, with
// multiplicity); NaN where fewer than min_patches are valid.
std::vector<double> MedianCurve(const Readings& readings,
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

double PredictedRadiusPx(const CalibrationCapture& c, double focus_mm) {
  const double f = c.lens.focal_length_mm;
  const double u_g = FocusObjectDistanceMm(focus_mm, f);
  const double u_t =
      ObjectDistanceFromSensorMm(c.target_distance_mm, focus_mm, f);
  return BlurRadiusPxFromDiameterMm(SignedBlurDiameterMm(c.lens, u_g, u_t),
                                    c.working_pitch_mm);
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

struct Solution {
  double focus_mm = kNaN;
  double kappa = kNaN;
  std::vector<double> capture_kappa;
  std::vector<double> cell_kappa;
  double strength = kNaN;  // see TargetCalibration::strength
  double near_kappa = kNaN, far_kappa = kNaN;
};

}  // namespace

bool TargetCalibrationOptions::Check() const {
  DPSFM_CHECK_NESTED_OPTIONS(blur);
  if (!SplitProfileParams::CheckCentroidOffsetRange(min_centroid_offset,
                                                    max_centroid_offset)) {
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

  // All patches in one list; capture and cell of each.
  std::vector<const ProfilePatch*> patches;
  std::vector<int> capture_of, cell_of;
  for (int i = 0; i < num_captures; ++i) {
    const CalibrationCapture& c = captures[i];
    DPSFM_CHECK(c.lens.Check() && c.working_pitch_mm > 0 &&
                c.target_distance_mm > 0)
        << "capture " << c.name << ": invalid lens data or distance";
    for (const ProfilePatch& p : c.patches) {
      patches.push_back(&p);
      capture_of.push_back(i);
      cell_of.push_back(out.layout.CellAt(p.x_fraction, p.y_fraction));
    }
  }
  const int n = static_cast<int>(patches.size());
  if (n == 0) {
    out.reason = "no textured patch in any capture";
    return finish();
  }
  const cv::Size size = patches[0]->left.size();
  for (const ProfilePatch* p : patches) {
    DPSFM_CHECK(p->left.type() == CV_32FC1 && p->left.size() == size &&
                p->right.size() == size)
        << "calibration patches must be CV_32FC1 crops of one size";
  }

  // Readings along the path (the expensive part), in parallel.
  const std::vector<double> kappas = GeometricNodes(options.min_centroid_offset,
                                                    options.max_centroid_offset,
                                                    options.node_ratio);
  Readings readings(kappas.size(), std::vector<double>(n, kNaN));
  for (size_t k = 0; k < kappas.size(); ++k) {
    const std::vector<PatchBlurEstimate> estimates = EstimateProfilePatches(
        SplitProfilePsf(SplitProfileParams::ForCentroidOffset(kappas[k])),
        options.blur,
        patches,
        options.num_threads);
    for (int p = 0; p < n; ++p) {
      if (estimates[p].valid) readings[k][p] = estimates[p].radius_px;
    }
  }
  // The linear split's node, for the "enough blur" test.
  const double linear = SplitProfileParams().CentroidOffset();
  size_t linear_node = 0;
  for (size_t k = 0; k < kappas.size(); ++k) {
    if (std::abs(std::log(kappas[k] / linear)) <
        std::abs(std::log(kappas[linear_node] / linear))) {
      linear_node = k;
    }
  }

  bool focus_unknown = false;
  for (const CalibrationCapture& c : captures) {
    focus_unknown = focus_unknown || !std::isfinite(c.focus_distance_mm);
  }
  std::vector<double> focus_grid;
  if (focus_unknown) {
    const double a = 1 / options.max_focus_mm, b = 1 / options.min_focus_mm;
    for (int k = 0; k < options.num_focus_steps; ++k) {
      focus_grid.push_back(1 /
                           (a + (b - a) * (k + 0.5) / options.num_focus_steps));
    }
  }

  std::vector<double> cell_weight(out.layout.NumCells(), 0);
  for (int p = 0; p < n; ++p) cell_weight[cell_of[p]] += 1;
  // One solution from patch members (with multiplicity) per capture.
  auto solve = [&](const std::vector<std::vector<int>>& members,
                   std::vector<double>* readings_px) -> Solution {
    Solution s;
    std::vector<std::vector<double>> curves(num_captures);
    std::vector<bool> blurred(num_captures, false);
    int num_blurred = 0;
    for (int i = 0; i < num_captures; ++i) {
      curves[i] = MedianCurve(readings, members[i], options.min_patches);
      const double r = curves[i][linear_node];
      if (readings_px) (*readings_px)[i] = r;
      blurred[i] = std::isfinite(r) && std::abs(r) >= options.min_reading_px;
      num_blurred += blurred[i] ? 1 : 0;
    }
    auto focus_of = [&](int i, double candidate) {
      return std::isfinite(captures[i].focus_distance_mm)
                 ? captures[i].focus_distance_mm
                 : candidate;
    };
    auto kappas_at = [&](double candidate) {
      std::vector<double> k(num_captures, kNaN);
      for (int i = 0; i < num_captures; ++i) {
        if (!blurred[i]) continue;
        const double f = focus_of(i, candidate);
        if (f < 4 * captures[i].lens.focal_length_mm) continue;
        k[i] = KappaForRadius(
            kappas, curves[i], PredictedRadiusPx(captures[i], f));
      }
      return k;
    };
    double focus = kNaN;
    if (!focus_unknown) {
      focus = 0;  // each capture's own
    } else if (num_blurred >= 2) {
      // The focus at which the most captures find a centroid offset (a
      // capture whose blur the family cannot reach at a candidate, e.g.
      // beyond the search bound, leaves it), and among those the one where
      // they agree best.
      const int needed = std::max(2, (num_blurred + 1) / 2);
      double best = std::numeric_limits<double>::infinity();
      int best_count = 0;
      for (const double candidate : focus_grid) {
        const std::vector<double> k = kappas_at(candidate);
        double sum = 0, sum2 = 0;
        int m = 0;
        for (int i = 0; i < num_captures; ++i) {
          if (!blurred[i] || !std::isfinite(k[i])) continue;
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
    if (!std::isfinite(focus)) return s;
    s.focus_mm = focus;
    s.capture_kappa = kappas_at(focus);
    s.kappa = GeometricMean(s.capture_kappa);
    std::vector<double> near, far;
    for (int i = 0; i < num_captures; ++i) {
      if (!std::isfinite(s.capture_kappa[i])) continue;
      (PredictedRadiusPx(captures[i], focus_of(i, focus)) < 0 ? near : far)
          .push_back(s.capture_kappa[i]);
    }
    s.near_kappa = GeometricMean(near);
    s.far_kappa = GeometricMean(far);
    // Cells: the same focus, each capture's patches in the cell.
    s.cell_kappa.assign(out.layout.NumCells(), kNaN);
    for (int c = 0; c < out.layout.NumCells(); ++c) {
      std::vector<double> k;
      for (int i = 0; i < num_captures; ++i) {
        if (!blurred[i]) continue;
        std::vector<int> in_cell;
        for (int p : members[i]) {
          if (cell_of[p] == c) in_cell.push_back(p);
        }
        const std::vector<double> curve =
            MedianCurve(readings, in_cell, options.min_patches);
        k.push_back(KappaForRadius(
            kappas, curve, PredictedRadiusPx(captures[i], focus_of(i, focus))));
      }
      s.cell_kappa[c] = GeometricMean(k);
    }
    double log_sum = 0, weight = 0;
    for (int c = 0; c < out.layout.NumCells(); ++c) {
      const double k =
          std::isfinite(s.cell_kappa[c]) ? s.cell_kappa[c] : s.kappa;
      log_sum += cell_weight[c] * std::log(k);
      weight += cell_weight[c];
    }
    s.strength = weight > 0 ? std::exp(log_sum / weight) : s.kappa;
    return s;
  };

  std::vector<std::vector<int>> all(num_captures);
  for (int p = 0; p < n; ++p) all[capture_of[p]].push_back(p);
  std::vector<double> reading_px(num_captures, kNaN);
  const Solution best = solve(all, &reading_px);
  out.focus_fitted = focus_unknown;
  int num_blurred = 0;
  for (int i = 0; i < num_captures; ++i) {
    const CalibrationCapture& c = captures[i];
    out.capture_names.push_back(c.name);
    out.capture_reading_px.push_back(reading_px[i]);
    const double focus = std::isfinite(c.focus_distance_mm)
                             ? c.focus_distance_mm
                             : best.focus_mm;
    out.capture_radius_px.push_back(
        std::isfinite(focus) ? PredictedRadiusPx(c, focus) : kNaN);
    out.capture_centroid_offset.push_back(
        best.capture_kappa.empty() ? kNaN : best.capture_kappa[i]);
    num_blurred += std::isfinite(reading_px[i]) &&
                           std::abs(reading_px[i]) >= options.min_reading_px
                       ? 1
                       : 0;
  }
  if (num_blurred == 0) {
    std::ostringstream s;
    s << "none of the " << num_captures
      << " captures shows visible blur (median reading under the linear "
         "split below "
      << options.min_reading_px
      << " px): the target was too close to the "
         "focus or the aperture too small";
    out.reason = s.str();
    return finish();
  }
  if (focus_unknown && num_blurred < 2) {
    std::ostringstream s;
    s << "with the focus distance unknown the profile needs two or more "
         "captures with visible blur at different distances; "
      << num_blurred << " of " << num_captures
      << " have blur (median reading >= " << options.min_reading_px
      << " px). Give focus_distance_m, or capture the target nearer and "
         "farther than the focus";
    out.reason = s.str();
    return finish();
  }
  if (!std::isfinite(best.kappa)) {
    std::ostringstream s;
    s << "no profile with a centroid offset in [" << options.min_centroid_offset
      << ", " << options.max_centroid_offset
      << "] R makes every capture's blur agree with its distance"
      << (focus_unknown ? " at any focus distance" : "")
      << " (check the distances, the focus, the lens data and the left/right "
         "order of the views)";
    out.reason = s.str();
    return finish();
  }
  // Given: the first capture's (each capture used its own).
  out.focus_distance_mm =
      focus_unknown ? best.focus_mm : captures[0].focus_distance_mm;
  out.centroid_offset = best.kappa;
  out.near_centroid_offset = best.near_kappa;
  out.far_centroid_offset = best.far_kappa;

  // Bootstrap over patches within each capture.
  std::vector<double> b_focus, b_kappa, b_strength;
  std::vector<std::vector<double>> b_cells(out.layout.NumCells());
  if (options.num_bootstrap > 0) {
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
      const Solution s = solve(members, nullptr);
      // A resample without a solution counts at the range's ends (it
      // widens the interval rather than vanishing from it).
      b_kappa.push_back(std::isfinite(s.kappa) ? s.kappa : kNaN);
      b_strength.push_back(std::isfinite(s.kappa) ? s.strength : kNaN);
      if (focus_unknown) b_focus.push_back(s.focus_mm);
      for (int c = 0; c < out.layout.NumCells(); ++c) {
        if (!s.cell_kappa.empty()) b_cells[c].push_back(s.cell_kappa[c]);
      }
    }
  }
  auto interval =
      [&](std::vector<double> v, double value, double* lo, double* hi) {
        const size_t total = v.size();
        v.erase(
            std::remove_if(
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
      };
  interval(b_kappa,
           out.centroid_offset,
           &out.centroid_offset_ci_low,
           &out.centroid_offset_ci_high);
  out.strength = best.strength;
  interval(
      b_strength, out.strength, &out.strength_ci_low, &out.strength_ci_high);
  if (focus_unknown) {
    interval(b_focus,
             out.focus_distance_mm,
             &out.focus_ci_low_mm,
             &out.focus_ci_high_mm);
  } else {
    out.focus_ci_low_mm = out.focus_ci_high_mm = out.focus_distance_mm;
  }
  for (int c = 0; c < out.layout.NumCells(); ++c) {
    int count = 0;
    for (int p = 0; p < n; ++p) count += cell_of[p] == c ? 1 : 0;
    out.cell_patches.push_back(count);
    const bool own = std::isfinite(best.cell_kappa[c]);
    out.cell_own.push_back(own);
    out.cell_centroid_offsets.push_back(own ? best.cell_kappa[c]
                                            : out.centroid_offset);
    double lo = out.centroid_offset_ci_low, hi = out.centroid_offset_ci_high;
    if (own) interval(b_cells[c], best.cell_kappa[c], &lo, &hi);
    out.cell_ci_low.push_back(lo);
    out.cell_ci_high.push_back(hi);
  }

  // The profile used is the cells' (the whole frame's where a cell has too
  // few patches). The overall strength is what the scale inherits, so it
  // must be determined to the limit; a cell only reads its own patches,
  // which a scene spreads over all cells, so a cell may be up to twice as
  // uncertain (linear light leaves the darker cells of 8-bit captures
  // noisier: the R6 II planes' edge cells are 11 % uncertain there, 6 % as
  // encoded). (The whole frame's own interval is wide when the profile
  // changes across the frame, its patches then being a mixture.)
  auto relative = [](double value, double lo, double hi) {
    return std::max(value - lo, hi - value) / value;
  };
  double worst_cell = 0;
  bool any_own = false;
  for (int c = 0; c < out.layout.NumCells(); ++c) {
    if (!out.cell_own[c]) continue;
    any_own = true;
    worst_cell = std::max(worst_cell,
                          relative(out.cell_centroid_offsets[c],
                                   out.cell_ci_low[c],
                                   out.cell_ci_high[c]));
  }
  if (!any_own || options.num_bootstrap == 0) {
    worst_cell = relative(out.centroid_offset,
                          out.centroid_offset_ci_low,
                          out.centroid_offset_ci_high);
  }
  out.worst_cell_uncertainty = worst_cell;
  const double strength_side =
      relative(out.strength, out.strength_ci_low, out.strength_ci_high);
  // As a fraction of the limit: the strength's side against 1 x, the worst
  // cell's against 2 x.
  double worst_side = std::isfinite(strength_side)
                          ? std::max(worst_cell / 2, strength_side)
                          : std::numeric_limits<double>::infinity();
  if (options.num_bootstrap == 0) worst_side = kNaN;
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
  if (!(worst_side <= options.max_relative_uncertainty)) {
    const bool strength_worse = !(strength_side <= worst_cell / 2);
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
    out.reason = s.str();
    return finish();
  }
  out.determined = true;
  out.reason = s.str();
  return finish();
}

}  // namespace dpsfm
