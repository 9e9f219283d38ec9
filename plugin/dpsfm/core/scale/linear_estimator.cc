#include "dpsfm/core/scale/linear_estimator.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
#include <random>
#include <sstream>

#include <Eigen/Dense>

#include "dpsfm/core/util/check.h"
#include "dpsfm/core/util/curve_math.h"
#include "dpsfm/core/util/statistics.h"
#include "dpsfm/core/util/threads.h"

namespace dpsfm {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string FormatDouble(double v, int precision = 3) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

// Minimiser of sum_k w_k |gamma_k x - c_k| over x: a weighted median of
// c_k / gamma_k with weights w_k |gamma_k| (exact 1-D L1).
double WeightedL1Fit1D(const std::vector<double>& gamma,
                       const std::vector<double>& c) {
  std::vector<std::pair<double, double>> items;
  double total = 0;
  for (size_t k = 0; k < gamma.size(); ++k) {
    if (gamma[k] == 0 || !std::isfinite(gamma[k]) || !std::isfinite(c[k])) {
      continue;
    }
    items.emplace_back(c[k] / gamma[k], std::abs(gamma[k]));
    total += std::abs(gamma[k]);
  }
  if (items.empty()) return kNaN;
  std::sort(items.begin(), items.end());
  double acc = 0;
  for (const auto& item : items) {
    acc += item.second;
    if (acc >= 0.5 * total) return item.first;
  }
  return items.back().first;
}

}  // namespace

double ReadingWeight(double radius_se_px) {
  if (!(radius_se_px > 0) || !std::isfinite(radius_se_px)) return 1;
  return 1 / std::hypot(radius_se_px, kRadiusErrorFloorPx);
}

bool IrlsOptions::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_GT(max_iterations, 0);
  DPSFM_CHECK_OPTION_GT(epsilon, 0);
  DPSFM_CHECK_OPTION_GT(tolerance, 0);
  return true;
}

bool LinearEstimatorOptions::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_GE(min_blur_range_px, 0);
  DPSFM_CHECK_OPTION_GT(num_selected_views, 0);
  DPSFM_CHECK_OPTION_GT(max_residual_to_range, 0);
  // A single-view solve has two unknowns.
  DPSFM_CHECK_OPTION_GE(min_samples_per_view, 2);
  DPSFM_CHECK_OPTION_GE(min_rcond, 0);
  DPSFM_CHECK_OPTION_GE(min_relative_depth_range, 0);
  DPSFM_CHECK_OPTION_GE(num_bootstrap, 0);
  DPSFM_CHECK_OPTION_VALUE(confidence_level > 0 && confidence_level < 1,
                           confidence_level);
  DPSFM_CHECK_OPTION_VALUE(num_threads == -1 || num_threads > 0, num_threads);
  DPSFM_CHECK_NESTED_OPTIONS(irls);
  return true;
}

bool LinearFailure::SwappedViewsLikely() const {
  return !view_rejections.empty() &&
         view_rejections[0].second == ViewRejection::kNonPositiveScale;
}

namespace {

// The system's weighted normal equations in column-scaled unknowns (unit
// weighted L2 norm per column): each row touches only (v, v), (v, n) and
// (n, n) of the normal matrix.
class ScaledNormalEquations {
 public:
  ScaledNormalEquations(const DPLinearSystem& system,
                        const std::vector<double>* row_weights)
      : system_(system),
        row_weights_(row_weights),
        n_(system.num_views),
        col_norm_(Eigen::VectorXd::Zero(n_ + 1)),
        normal_(n_ + 1, n_ + 1),
        rhs_(n_ + 1) {
    for (int k = 0; k < system.NumRows(); ++k) {
      const int v = system.row_view[k];
      DPSFM_CHECK(v >= 0 && v < n_) << "row " << k << " has view " << v;
      const double w = RowWeight(k);
      col_norm_[v] += w * system.rows[k].gamma * system.rows[k].gamma;
      col_norm_[n_] += w * system.rows[k].minus_l * system.rows[k].minus_l;
    }
    col_norm_ = col_norm_.cwiseSqrt();
  }

  // Every column has a finite, positive norm.
  bool ColumnsUsable() const {
    return col_norm_.allFinite() && (col_norm_.array() > 0).all();
  }
  // The row's precision times the caller's weight.
  double RowWeight(int k) const {
    const double precision =
        system_.row_weight.empty() ? 1.0 : system_.row_weight[k];
    return precision * (row_weights_ == nullptr ? 1.0 : (*row_weights_)[k]);
  }
  // Assembles the equations with `weights` (null: RowWeight).
  void Assemble(const Eigen::VectorXd* weights) {
    normal_.setZero();
    rhs_.setZero();
    for (int k = 0; k < system_.NumRows(); ++k) {
      const int v = system_.row_view[k];
      const double w = weights == nullptr ? RowWeight(k) : (*weights)[k];
      if (w == 0) continue;
      const double a0 = system_.rows[k].gamma / col_norm_[v];
      const double a1 = system_.rows[k].minus_l / col_norm_[n_];
      const double b = system_.rows[k].rhs;
      normal_(v, v) += w * a0 * a0;
      normal_(v, n_) += w * a0 * a1;
      normal_(n_, n_) += w * a1 * a1;
      rhs_[v] += w * a0 * b;
      rhs_[n_] += w * a1 * b;
    }
    for (int v = 0; v < n_; ++v) normal_(n_, v) = normal_(v, n_);
  }
  // The assembled matrix's reciprocal condition number.
  double Rcond() const {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(normal_,
                                                       Eigen::EigenvaluesOnly);
    const double lmax = eig.eigenvalues().maxCoeff();
    const double lmin = eig.eigenvalues().minCoeff();
    return lmax > 0 ? std::max(0.0, lmin / lmax) : 0.0;
  }
  // The assembled equations' solution, in scaled unknowns.
  Eigen::VectorXd Solve() const { return normal_.ldlt().solve(rhs_); }
  // Each row's residual at the scaled unknowns y.
  Eigen::VectorXd Residuals(const Eigen::VectorXd& y) const {
    Eigen::VectorXd r(system_.NumRows());
    for (int k = 0; k < system_.NumRows(); ++k) {
      const int v = system_.row_view[k];
      r[k] = system_.rows[k].gamma / col_norm_[v] * y[v] +
             system_.rows[k].minus_l / col_norm_[n_] * y[n_] -
             system_.rows[k].rhs;
    }
    return r;
  }
  // The unknowns of the unscaled system.
  Eigen::VectorXd Unscaled(const Eigen::VectorXd& y) const {
    return y.cwiseQuotient(col_norm_);
  }

 private:
  const DPLinearSystem& system_;
  const std::vector<double>* row_weights_;
  const int n_;
  Eigen::VectorXd col_norm_;
  Eigen::MatrixXd normal_;
  Eigen::VectorXd rhs_;
};

}  // namespace

IrlsResult SolveL1Irls(const DPLinearSystem& system,
                       const IrlsOptions& options,
                       const std::vector<double>* row_weights) {
  DPSFM_CHECK_OPTIONS(options, "IrlsOptions");
  const int num_rows = system.NumRows();
  DPSFM_CHECK_EQ(system.row_view.size(), system.rows.size());
  if (row_weights != nullptr) {
    DPSFM_CHECK_EQ(static_cast<int>(row_weights->size()), num_rows);
  }
  IrlsResult result;
  if (system.num_views <= 0 || num_rows < system.num_views + 1) return result;
  DPSFM_CHECK(system.row_weight.empty() ||
              static_cast<int>(system.row_weight.size()) == num_rows);
  ScaledNormalEquations equations(system, row_weights);
  if (!equations.ColumnsUsable()) return result;
  equations.Assemble(nullptr);
  result.rcond = equations.Rcond();
  if (!(result.rcond > 1e-15)) return result;
  Eigen::VectorXd y = equations.Solve();  // first pass: plain least squares
  if (!y.allFinite()) return result;

  Eigen::VectorXd weights(num_rows);
  for (int it = 1; it <= options.max_iterations; ++it) {
    const Eigen::VectorXd r = equations.Residuals(y);
    for (int k = 0; k < num_rows; ++k) {
      weights[k] =
          equations.RowWeight(k) / std::max(std::abs(r[k]), options.epsilon);
    }
    equations.Assemble(&weights);
    const Eigen::VectorXd y_new = equations.Solve();
    result.iterations = it;
    if (!y_new.allFinite()) break;  // keep the last finite iterate
    const double step = (y_new - y).norm();
    y = y_new;
    if (step <= options.tolerance * std::max(y.norm(), 1e-300)) {
      result.converged = true;
      break;
    }
  }
  result.x = equations.Unscaled(y);
  result.residuals = equations.Residuals(y);
  result.success = result.x.allFinite();
  return result;
}

std::vector<int> SelectViewsNearMedian(const std::vector<double>& scales,
                                       const std::vector<bool>& eligible,
                                       int count) {
  DPSFM_CHECK_EQ(scales.size(), eligible.size());
  DPSFM_CHECK_GT(count, 0);
  std::vector<int> candidates;
  std::vector<double> log_scales;
  for (size_t i = 0; i < scales.size(); ++i) {
    if (eligible[i] && scales[i] > 0 && std::isfinite(scales[i])) {
      candidates.push_back(static_cast<int>(i));
      log_scales.push_back(std::log(scales[i]));
    }
  }
  if (static_cast<int>(candidates.size()) <= count) return candidates;
  // Scales are ratios, so "nearest" is measured in log ratio; the median is
  // the same in either space up to the even-count midpoint.
  const double median = Median(log_scales);
  std::vector<int> order(candidates.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return std::abs(log_scales[a] - median) < std::abs(log_scales[b] - median);
  });
  std::vector<int> selected;
  for (int k = 0; k < count; ++k) selected.push_back(candidates[order[k]]);
  std::sort(selected.begin(), selected.end());
  return selected;
}

namespace {

DPLinearSystem BuildSystem(const std::vector<LinearViewData>& views,
                           const std::vector<int>& subset) {
  DPLinearSystem system;
  system.num_views = static_cast<int>(subset.size());
  for (size_t c = 0; c < subset.size(); ++c) {
    const LinearViewData& view = views[subset[c]];
    for (const LinearSample& sample : view.samples) {
      system.AddRow(
          static_cast<int>(c),
          MakeLinearRow(
              view.lens, view.pixel_pitch_mm, sample.radius_px, sample.depth),
          ReadingWeight(sample.radius_se_px));
    }
  }
  return system;
}

LinearFailure FailureFromCounts(const std::vector<LinearViewResult>& results,
                                const LinearEstimatorOptions& options) {
  std::map<ViewRejection, int> counts;
  for (const auto& r : results) counts[r.rejection]++;
  LinearFailure failure;
  failure.cause = LinearFailureCause::kNoViewSelected;
  failure.min_blur_range_px = options.min_blur_range_px;
  for (const auto& kv : counts) {
    failure.view_rejections.emplace_back(kv.second, kv.first);
  }
  std::stable_sort(
      failure.view_rejections.begin(),
      failure.view_rejections.end(),
      [](const std::pair<int, ViewRejection>& a,
         const std::pair<int, ViewRejection>& b) { return a.first > b.first; });
  return failure;
}

// The per-view checks before a fit: enough samples, depth variation (with
// one depth, eq. (one_pixel) is still solvable when the blur varies (b sits
// in gamma) but only by g = f, a meaningless fit), and T_p on the measured
// blur (the paper's test: a view whose patches all show about the same blur
// cannot separate s from g_i, and its fit would only report noise, e.g. a
// random sign of s). False with out's rejection set when one fails.
bool CheckViewSamples(const LinearViewData& view,
                      const LinearEstimatorOptions& options,
                      LinearViewResult* out) {
  if (out->num_samples < options.min_samples_per_view) {
    out->rejection = ViewRejection::kTooFewPatches;
    out->reason = std::to_string(out->num_samples) +
                  " selected patches, need at least " +
                  std::to_string(options.min_samples_per_view);
    return false;
  }
  double imin = std::numeric_limits<double>::infinity(), imax = 0;
  for (const LinearSample& sample : view.samples) {
    imin = std::min(imin, 1.0 / sample.depth);
    imax = std::max(imax, 1.0 / sample.depth);
  }
  if (!(imax - imin > options.min_relative_depth_range * imax)) {
    out->rejection = ViewRejection::kDegenerate;
    out->reason =
        "no depth variation among its selected patches "
        "(inverse-depth range " +
        FormatDouble(100 * (imax - imin) / imax) + " %)";
    return false;
  }
  double rmin = std::numeric_limits<double>::infinity(), rmax = -rmin;
  for (const LinearSample& sample : view.samples) {
    rmin = std::min(rmin, sample.radius_px);
    rmax = std::max(rmax, sample.radius_px);
  }
  if (!(rmax - rmin > options.min_blur_range_px)) {
    out->rejection = ViewRejection::kSmallBlurRange;
    out->predicted_blur_range_px = rmax - rmin;
    out->reason = "measured blur range " + FormatDouble(rmax - rmin) +
                  " px <= T_p = " + FormatDouble(options.min_blur_range_px) +
                  " px (too little blur or depth variation)";
    return false;
  }
  return true;
}

// Range of the blur radii the single-view fit predicts for the samples.
double PredictedBlurRange(const LinearViewData& view,
                          const LinearViewResult& out) {
  double rmin = std::numeric_limits<double>::infinity();
  double rmax = -rmin;
  for (const LinearSample& sample : view.samples) {
    const double r = PredictBlurRadiusPx(view.lens,
                                         view.pixel_pitch_mm,
                                         out.single_scale,
                                         out.single_focus_model,
                                         sample.depth);
    rmin = std::min(rmin, r);
    rmax = std::max(rmax, r);
  }
  return rmax - rmin;
}

// Each view's readings with the scatter their standard errors do not
// explain added to them (in quadrature): the spread of the residuals of the
// view's unweighted fit (1.4826 x their median absolute value) beyond the
// readings' median standard error. The curve's standard error is the
// noise's alone; a real scene adds what no single patch's curve can see
// (depth errors, a kernel that differs across the frame). Where that
// dominates, the readings weigh nearly alike, as in the paper's fit; where
// noise dominates, by their precision.
std::vector<LinearViewData> WithMisfitInErrors(
    const std::vector<LinearViewData>& views,
    const LinearEstimatorOptions& options) {
  std::vector<LinearViewData> out = views;
  for (size_t i = 0; i < out.size(); ++i) {
    std::vector<LinearSample>& samples = out[i].samples;
    std::vector<double> se2;
    for (const LinearSample& s : samples) {
      if (s.radius_se_px > 0 && std::isfinite(s.radius_se_px)) {
        se2.push_back(s.radius_se_px * s.radius_se_px);
      }
    }
    if (se2.size() != samples.size() ||
        static_cast<int>(samples.size()) < options.min_samples_per_view) {
      continue;
    }
    DPLinearSystem system = BuildSystem(views, {static_cast<int>(i)});
    system.row_weight.clear();
    const IrlsResult fit = SolveL1Irls(system, options.irls);
    if (!fit.success) continue;
    std::vector<double> abs_res(fit.residuals.size());
    for (int k = 0; k < fit.residuals.size(); ++k) {
      abs_res[k] = std::abs(fit.residuals[k]);
    }
    const double spread = 1.4826 * Median(abs_res);
    const double misfit2 = std::max(0.0, spread * spread - Median(se2));
    for (LinearSample& s : samples) {
      s.radius_se_px = std::sqrt(s.radius_se_px * s.radius_se_px + misfit2);
    }
  }
  return out;
}

// View i's own solve and the checks on its result (a positive scale, a
// physical focus, enough predicted blur range, residuals small against
// it). True when the view is eligible for the joint solve.
bool FitSingleView(const std::vector<LinearViewData>& views,
                   int i,
                   const LinearEstimatorOptions& options,
                   LinearViewResult* out) {
  const LinearViewData& view = views[i];
  const IrlsResult fit = SolveL1Irls(BuildSystem(views, {i}), options.irls);
  if (!fit.success || fit.rcond < options.min_rcond) {
    out->rejection = ViewRejection::kDegenerate;
    out->reason =
        "single-view system is rank deficient (no depth variation among "
        "its patches; rcond " +
        FormatDouble(fit.rcond) + ")";
    return false;
  }
  const double gbar = fit.x[0];
  const double sbar = fit.x[1];
  if (!(sbar > 0)) {
    out->rejection = ViewRejection::kNonPositiveScale;
    out->reason =
        "single-view fit gives s <= 0 (blur does not grow with "
        "depth as the lens model predicts)";
    return false;
  }
  out->single_solved = true;
  out->single_scale = ScaleFromSbar(sbar);
  if (!(gbar > 0)) {
    out->rejection = ViewRejection::kNonPositiveFocus;
    out->reason = "single-view fit gives focus distance <= 0 or at infinity";
    return false;
  }
  out->single_focus_model = FocusModelFromUnknowns(gbar, sbar);
  if (gbar >= 1.0 / view.lens.focal_length_mm) {
    out->rejection = ViewRejection::kFocusBelowFocalLength;
    out->reason =
        "single-view fit puts the focus closer than the focal "
        "length";
    return false;
  }
  out->predicted_blur_range_px = PredictedBlurRange(view, *out);
  if (!(out->predicted_blur_range_px > options.min_blur_range_px)) {
    out->rejection = ViewRejection::kSmallBlurRange;
    out->reason =
        "predicted blur range " + FormatDouble(out->predicted_blur_range_px) +
        " px <= T_p = " + FormatDouble(options.min_blur_range_px) + " px";
    return false;
  }
  std::vector<double> abs_res(fit.residuals.size());
  for (int k = 0; k < fit.residuals.size(); ++k) {
    abs_res[k] = std::abs(fit.residuals[k]);
  }
  const double median_res = Median(abs_res);
  if (!(median_res <=
        options.max_residual_to_range * out->predicted_blur_range_px)) {
    out->rejection = ViewRejection::kPoorFit;
    out->reason = "blur does not follow depth: median residual " +
                  FormatDouble(median_res) + " px against a blur range of " +
                  FormatDouble(out->predicted_blur_range_px) + " px";
    return false;
  }
  return true;
}

// Eligible views left out of the N_v nearest the median say so.
void MarkFarFromMedian(const std::vector<double>& single_scales,
                       const std::vector<bool>& eligible,
                       const std::vector<int>& selected,
                       const LinearEstimatorOptions& options,
                       LinearEstimate* estimate) {
  const int num_views = static_cast<int>(eligible.size());
  std::vector<double> eligible_scales;
  for (int i = 0; i < num_views; ++i) {
    if (eligible[i]) eligible_scales.push_back(single_scales[i]);
  }
  const double median = Median(eligible_scales);
  for (int i = 0; i < num_views; ++i) {
    if (eligible[i] &&
        !std::binary_search(selected.begin(), selected.end(), i)) {
      estimate->views[i].rejection = ViewRejection::kFarFromMedian;
      estimate->views[i].reason =
          "single-view scale " + FormatDouble(single_scales[i]) +
          " is not among the " + std::to_string(options.num_selected_views) +
          " nearest the median " + FormatDouble(median);
    }
  }
}

// The joint solve of the selected views. A kept view whose joint focus
// comes out non-physical is dropped (its rejection set) and the solve
// repeated, at most once per view.
IrlsResult SolveJoint(const std::vector<LinearViewData>& views,
                      const LinearEstimatorOptions& options,
                      std::vector<int>* selected,
                      LinearEstimate* estimate) {
  IrlsResult joint;
  while (!selected->empty()) {
    joint = SolveL1Irls(BuildSystem(views, *selected), options.irls);
    if (!joint.success) break;
    const int n = static_cast<int>(selected->size());
    int worst = -1;
    for (int c = 0; c < n; ++c) {
      const double gbar = joint.x[c];
      if (!(gbar > 0) ||
          gbar >= 1.0 / views[(*selected)[c]].lens.focal_length_mm) {
        worst = c;
        break;
      }
    }
    if (worst < 0 || !(joint.x[n] > 0)) break;
    const int view = (*selected)[worst];
    estimate->views[view].rejection = ViewRejection::kNonPositiveFocus;
    estimate->views[view].reason =
        "joint fit gives a non-physical focus distance for this view";
    selected->erase(selected->begin() + worst);
  }
  return joint;
}

// Focus distances and residuals of every view under the joint scale (a view
// outside the joint solve gets its own focus by a 1-D L1 fit).
void FitViewsUnderJointScale(const std::vector<LinearViewData>& views,
                             const std::vector<int>& selected,
                             const IrlsResult& joint,
                             double sbar,
                             LinearEstimate* estimate) {
  for (int i = 0; i < static_cast<int>(views.size()); ++i) {
    LinearViewResult& out = estimate->views[i];
    const auto it = std::lower_bound(selected.begin(), selected.end(), i);
    const bool used = it != selected.end() && *it == i;
    out.used = used;
    if (used) {
      out.rejection = ViewRejection::kNone;
      out.reason = "used";
    }
    if (views[i].samples.empty()) continue;
    const DPLinearSystem system = BuildSystem(views, {i});
    std::vector<double> gamma, c;
    for (const LinearRow& row : system.rows) {
      gamma.push_back(row.gamma);
      c.push_back(row.rhs - row.minus_l * sbar);
    }
    const double gbar =
        used ? joint.x[it - selected.begin()] : WeightedL1Fit1D(gamma, c);
    out.focus_model = gbar > 0 ? FocusModelFromUnknowns(gbar, sbar) : kNaN;
    std::vector<double> abs_res;
    for (size_t k = 0; k < gamma.size(); ++k) {
      abs_res.push_back(std::abs(gamma[k] * gbar - c[k]));
    }
    out.median_abs_residual_px = Median(abs_res);
  }
}

// Bootstrap: resample rows within each kept view (stratified, so every
// column keeps its rows) and re-solve; the scale's interval, or why there
// is none, and each kept view's focus samples.
void BootstrapScaleInterval(const std::vector<LinearViewData>& views,
                            const std::vector<int>& selected,
                            const LinearEstimatorOptions& options,
                            LinearEstimate* estimate) {
  const int n = static_cast<int>(selected.size());
  const DPLinearSystem system = BuildSystem(views, selected);
  std::vector<std::vector<int>> rows_of_view(n);
  for (int k = 0; k < system.NumRows(); ++k) {
    rows_of_view[system.row_view[k]].push_back(k);
  }
  std::mt19937_64 rng(options.seed);
  IrlsOptions irls = options.irls;
  irls.max_iterations = std::min(irls.max_iterations, 200);
  irls.tolerance = std::max(irls.tolerance, 1e-7);
  // The resamples drawn in order (one random stream), then solved in
  // parallel, each from its own weights: the same at any thread count.
  const int num_resamples = options.num_bootstrap;
  std::vector<std::vector<double>> weights(
      num_resamples, std::vector<double>(system.NumRows(), 0.0));
  for (int b = 0; b < num_resamples; ++b) {
    for (const auto& rows : rows_of_view) {
      std::uniform_int_distribution<size_t> pick(0, rows.size() - 1);
      for (size_t k = 0; k < rows.size(); ++k) weights[b][rows[pick(rng)]] += 1;
    }
  }
  std::vector<IrlsResult> fits(num_resamples);
  ParallelFor(num_resamples, options.num_threads, [&](int b) {
    fits[b] = SolveL1Irls(system, irls, &weights[b]);
  });
  std::vector<double> samples;
  for (const IrlsResult& fit : fits) {
    const bool solved = fit.success && fit.x[n] > 0;
    if (solved) samples.push_back(ScaleFromSbar(fit.x[n]));
    for (int j = 0; j < n; ++j) {
      estimate->views[selected[j]].focus_model_samples.push_back(
          solved && fit.x[j] > 0 ? FocusModelFromUnknowns(fit.x[j], fit.x[n])
                                 : kNaN);
    }
  }
  if (samples.size() >= 10) {
    const double alpha = 0.5 * (1.0 - options.confidence_level);
    estimate->scale_ci_low =
        std::min(estimate->scale, Percentile(samples, alpha));
    estimate->scale_ci_high =
        std::max(estimate->scale, Percentile(samples, 1.0 - alpha));
    estimate->interval_status.clear();
  } else {
    estimate->interval_status = "only " + std::to_string(samples.size()) +
                                " of " + std::to_string(options.num_bootstrap) +
                                " bootstrap resamples solved, need 10";
  }
}

}  // namespace

LinearEstimate EstimateScaleLinear(const std::vector<LinearViewData>& given,
                                   const LinearEstimatorOptions& options) {
  DPSFM_CHECK_OPTIONS(options, "LinearEstimatorOptions");
  const std::vector<LinearViewData> views = WithMisfitInErrors(given, options);
  LinearEstimate estimate;
  const int num_views = static_cast<int>(views.size());
  estimate.views.resize(num_views);
  if (num_views == 0) {
    estimate.failure.cause = LinearFailureCause::kNoViews;
    return estimate;
  }

  // --- Per-view solves. ---
  std::vector<double> single_scales(num_views, kNaN);
  std::vector<bool> eligible(num_views, false);
  for (int i = 0; i < num_views; ++i) {
    const LinearViewData& view = views[i];
    LinearViewResult& out = estimate.views[i];
    DPSFM_CHECK(view.lens.Check())
        << "view '" << view.name << "' has invalid lens data ("
        << view.lens.ToString() << ")";
    DPSFM_CHECK_GT(view.pixel_pitch_mm, 0);
    out.num_samples = static_cast<int>(view.samples.size());
    out.focus_model = kNaN;
    if (!CheckViewSamples(view, options, &out)) continue;
    eligible[i] = FitSingleView(views, i, options, &out);
    if (out.single_solved) single_scales[i] = out.single_scale;
  }

  // --- N_v views nearest the median; the joint solve. ---
  std::vector<int> selected = SelectViewsNearMedian(
      single_scales, eligible, options.num_selected_views);
  MarkFarFromMedian(single_scales, eligible, selected, options, &estimate);
  if (selected.empty()) {
    estimate.failure = FailureFromCounts(estimate.views, options);
    return estimate;
  }
  const IrlsResult joint = SolveJoint(views, options, &selected, &estimate);
  if (selected.empty()) {
    estimate.failure = FailureFromCounts(estimate.views, options);
    return estimate;
  }
  const int n = static_cast<int>(selected.size());
  if (!joint.success || !(joint.x[n] > 0)) {
    estimate.failure.cause = !joint.success
                                 ? LinearFailureCause::kRankDeficient
                                 : LinearFailureCause::kNonPositiveScale;
    return estimate;
  }
  estimate.success = true;
  estimate.selected_views = selected;
  estimate.scale = ScaleFromSbar(joint.x[n]);
  estimate.num_rows = static_cast<int>(joint.residuals.size());
  estimate.irls_iterations = joint.iterations;
  const Eigen::VectorXd abs_res = joint.residuals.cwiseAbs();
  estimate.median_abs_residual_px = Median(
      std::vector<double>(abs_res.data(), abs_res.data() + abs_res.size()));
  FitViewsUnderJointScale(views, selected, joint, joint.x[n], &estimate);

  estimate.scale_ci_low = estimate.scale_ci_high = kNaN;
  estimate.interval_status = "num_bootstrap is 0";
  if (options.num_bootstrap > 0) {
    BootstrapScaleInterval(views, selected, options, &estimate);
  }
  return estimate;
}

}  // namespace dpsfm
