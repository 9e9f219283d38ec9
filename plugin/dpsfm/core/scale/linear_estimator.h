// Linear initial estimate of the scale (paper sec. "Initial Estimation" and
// "View Selection"): the sparse (views + 1)-column system of eq.
// (linear_system), solved by L1 IRLS with column scaling, per-view solves,
// view selection and the joint solve.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "dpsfm/core/optics/lens_model.h"

namespace dpsfm {

// ---------------------------------------------------------------------------
// The sparse system. Row k belongs to view row_view[k] and has two non-zeros:
// `gamma` in that view's column and `minus_l` in the last (shared) column.
// Unknowns x = [gbar_1 .. gbar_n, sbar] (see lens_model.h).
// Each row's L1 term is multiplied by its weight: the precision of its blur
// reading (LinearSample::radius_se_px), 1 when none is known.
struct DPLinearSystem {
  int num_views = 0;
  std::vector<int> row_view;
  std::vector<LinearRow> rows;
  std::vector<double> row_weight;

  int NumRows() const { return static_cast<int>(rows.size()); }
  void AddRow(int view, const LinearRow& row, double weight = 1) {
    row_view.push_back(view);
    rows.push_back(row);
    row_weight.push_back(weight);
  }
};

struct IrlsOptions {
  // Hard cap on reweighting passes (the reference code's 1000).
  int max_iterations = 1000;
  // Residual floor of the weights 1/max(|r|, epsilon), in the rows' unit
  // (pixels of blur radius). Small enough to reach the L1 optimum, large
  // enough that an exactly fitted row cannot make the normal matrix singular.
  double epsilon = 1e-6;
  // Stop when the column-scaled solution moves less than this (relative).
  double tolerance = 1e-9;
  bool Check(std::string* failure = nullptr) const;
};

struct IrlsResult {
  bool success = false;       // false: rank deficient or non-finite
  Eigen::VectorXd x;          // unknowns in natural units
  Eigen::VectorXd residuals;  // A x - b per row (px)
  int iterations = 0;
  bool converged = false;
  // Reciprocal condition number of the column-scaled normal matrix of the
  // unweighted system (1 = perfect, ~0 = no depth variation / rank n+1 lost).
  double rcond = 0;
};

// min ||A x - b||_1 by IRLS (first pass plain least squares, then weights
// 1 / max(|r|, eps)). Columns are scaled to unit norm before solving because
// gbar (~1e-3/mm) and sbar differ by orders of magnitude. The normal matrix
// is assembled from the two non-zeros of each row, so the cost is
// O(rows + views^3) per pass. `row_weights` (optional, >= 0) multiply the
// L1 terms (used by the bootstrap).
IrlsResult SolveL1Irls(const DPLinearSystem& system,
                       const IrlsOptions& options,
                       const std::vector<double>* row_weights = nullptr);

// ---------------------------------------------------------------------------
// View selection and the joint solve.

struct LinearSample {
  double depth = 0;      // z' in model units (> 0)
  double radius_px = 0;  // signed blur radius (> 0 farther than focus)
  // Standard error of radius_px from its loss curve (px; 0 = unknown). The
  // row's L1 term is weighted by ReadingWeight of it, after the view's
  // scatter that the standard errors do not explain is added to them (the
  // spread of an unweighted fit's residuals beyond their median standard
  // error, in quadrature).
  double radius_se_px = 0;
};

// What a blur reading can never be more precise than, whatever its curve
// says (px): the kernel grid's shape error and the model's (a real lens is
// not a thin lens, a patch not one depth) are not in the curve's noise.
constexpr double kRadiusErrorFloorPx = 0.1;

// The weight of a reading of standard error se in the L1 fit.
double ReadingWeight(double radius_se_px);

struct LinearViewData {
  std::string name;
  DPLensData lens;
  // Pitch of the pixels radius_px is measured in (mm); differs from
  // lens.PixelPitchMm() when the frame was resized before blur estimation.
  double pixel_pitch_mm = 0;
  // The view's selected (top-T_c) patches.
  std::vector<LinearSample> samples;
};

struct LinearEstimatorOptions {
  // T_p: a view whose measured blur range (max - min signed radius over its
  // patches), or the range its single-view fit predicts, is at most this
  // many pixels is dropped: too little depth variation for a stable solve.
  double min_blur_range_px = 2.0;
  // A view whose single-view fit leaves a median |residual| above this
  // fraction of its predicted blur range is dropped: its blur does not follow
  // its depth (noise fitted as blur, motion blur, wrong depth). Noise-only
  // patches fit with residuals comparable to the range; clean ones at a few
  // percent of it.
  double max_residual_to_range = 0.3;
  // N_v: views kept nearest the median single-view scale.
  int num_selected_views = 7;
  // A view needs this many samples for its own solve (2 is the algebraic
  // minimum; a robust L1 fit wants a few more).
  int min_samples_per_view = 4;
  // Single-view fits whose system is this close to rank deficient (rcond of
  // the column-scaled normal matrix) are rejected.
  double min_rcond = 1e-10;
  // ...and so are views whose patches span less than this relative range of
  // inverse depth, (max - min) / max.
  double min_relative_depth_range = 0.01;
  IrlsOptions irls;
  // Bootstrap resamples (rows resampled within each kept view) for the
  // confidence interval of the joint scale; 0 disables it.
  int num_bootstrap = 200;
  // Central probability mass of the reported interval.
  double confidence_level = 0.95;
  uint64_t seed = 42;
  // OpenMP threads for the bootstrap's solves (the resamples are drawn in
  // order first, so the interval is the same at any count); -1 = all.
  int num_threads = -1;
  bool Check(std::string* failure = nullptr) const;
};

enum class ViewRejection {
  kNone = 0,
  kTooFewPatches,
  kDegenerate,
  kNonPositiveScale,
  kNonPositiveFocus,
  kFocusBelowFocalLength,
  kSmallBlurRange,
  kPoorFit,
  kFarFromMedian,
};

struct LinearViewResult {
  bool used = false;
  ViewRejection rejection = ViewRejection::kNone;
  std::string reason;  // human readable, with the numbers
  int num_samples = 0;
  // Single-view solve (valid when single_solved).
  bool single_solved = false;
  double single_scale = 0;        // metres per model unit
  double single_focus_model = 0;  // g' (model units)
  double predicted_blur_range_px = 0;
  // g' under the joint scale: from the joint solve for used views, from an L1
  // fit with s fixed for the others (NaN when the view has no samples).
  double focus_model = 0;
  // g' in each bootstrap resample, aligned across the used views (NaN where
  // a resample did not solve); empty for views not used.
  std::vector<double> focus_model_samples;
  double median_abs_residual_px = 0;  // under the joint solution
};

// Why the linear stage gave no scale.
enum class LinearFailureCause {
  kNone,
  kNoViews,
  kNoViewSelected,    // every view was rejected (view_rejections)
  kRankDeficient,     // the joint system of the selected views
  kNonPositiveScale,  // the joint fit gives s <= 0
};

struct LinearFailure {
  LinearFailureCause cause = LinearFailureCause::kNone;
  // kNoViewSelected: (views, rejection), the most frequent first (ties in
  // the order of ViewRejection).
  std::vector<std::pair<int, ViewRejection>> view_rejections;
  // T_p (LinearEstimatorOptions::min_blur_range_px), the threshold of
  // ViewRejection::kSmallBlurRange.
  double min_blur_range_px = 0;

  // Most views were rejected for s <= 0: blur that shrinks with depth,
  // which usually means the left and right DP views are swapped.
  bool SwappedViewsLikely() const;
};

struct LinearEstimate {
  bool success = false;
  LinearFailure failure;
  double scale = 0;  // s* (metres per model unit)
  // The bootstrap's interval; NaN when it could not be measured
  // (num_bootstrap 0, or fewer than 10 resamples solved), and then
  // interval_status says why.
  double scale_ci_low = 0, scale_ci_high = 0;
  std::string interval_status;
  std::vector<LinearViewResult> views;
  std::vector<int> selected_views;
  int num_rows = 0;  // rows in the joint system
  double median_abs_residual_px = 0;
  int irls_iterations = 0;
};

// Per-view solves, selection (measured or predicted blur range <= T_p,
// s <= 0, g <= 0, g <= f rejected; N_v nearest the median kept) and the joint
// solve.
LinearEstimate EstimateScaleLinear(const std::vector<LinearViewData>& views,
                                   const LinearEstimatorOptions& options);

// The N_v selection on its own: among `eligible` views, the `count` whose
// scale is nearest (in log ratio) to the median of the eligible scales; ties
// by index. Returns sorted indices. Correct for any number of views.
std::vector<int> SelectViewsNearMedian(const std::vector<double>& scales,
                                       const std::vector<bool>& eligible,
                                       int count);

}  // namespace dpsfm
