#include "dpsfm/core/blur/blur_estimation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "dpsfm/core/blur/blur_search_internal.h"
#include "dpsfm/core/util/check.h"

namespace dpsfm {

const char* const kBlurAtSearchBound = "blur beyond the search bound";
const char* const kBlurUndetermined =
    "blur not determined (its loss curve is within the patch's noise)";

namespace {

using internal::BlurRefinement;
using internal::BlurTables;
using internal::CoarseCurve;
using Minimum = BlurRefinement::Minimum;

constexpr double kInf = std::numeric_limits<double>::infinity();

bool AllFinite(const cv::Mat& image) {
  for (int y = 0; y < image.rows; ++y) {
    const float* row = image.ptr<float>(y);
    for (int x = 0; x < image.cols; ++x) {
      if (!std::isfinite(row[x])) {
        return false;
      }
    }
  }
  return true;
}

// Mean |horizontal Sobel| of left + right.
double ViewsTexture(const cv::Mat& left, const cv::Mat& right) {
  cv::Mat sum;
  cv::add(left, right, sum);
  return HorizontalTexture(sum);
}

// The gain-equalised views minus their common mean `offset`.
struct EqualisedViews {
  cv::Mat gl, gr;
  double offset = 0;
};

// Gain equalisation: scale both views to their common mean, then remove
// it. The residual is unchanged by the mean removal (both kernels of a pair
// pass the same DC), and float precision improves. False when a view is
// too dark to equalise.
bool EqualiseViews(const cv::Mat& left,
                   const cv::Mat& right,
                   const BlurEstimationOptions& options,
                   EqualisedViews* views) {
  const double mean_left = cv::mean(left)[0];
  const double mean_right = cv::mean(right)[0];
  double gain_left = 1, gain_right = 1;
  if (options.normalize_gain) {
    if (!(mean_left > 1e-6 && mean_right > 1e-6)) return false;
    const double common = 0.5 * (mean_left + mean_right);
    gain_left = common / mean_left;
    gain_right = common / mean_right;
  }
  views->offset = 0.5 * (mean_left * gain_left + mean_right * gain_right);
  left.convertTo(views->gl, CV_32FC1, gain_left, -views->offset);
  right.convertTo(views->gr, CV_32FC1, gain_right, -views->offset);
  return true;
}

// Noise: the smaller of the views' and the difference's estimates
// (PairNoiseVariance). The refinement tightens it further with the fit
// itself. inf without the noise floor's subtraction.
double PatchNoiseVariance(const cv::Mat& gl,
                          const cv::Mat& gr,
                          const BlurEstimationOptions& options) {
  if (!options.subtract_noise_floor) return kInf;
  return PairNoiseVariance(gl, gr);
}

// The exact minimum from the coarse search's best basin (and a second one
// of similar coarse loss), with the gain re-derived at the estimate.
Minimum RefineCoarseMinima(const BlurTables& t,
                           const CoarseCurve& coarse,
                           BlurRefinement* refinement) {
  const BlurEstimationOptions& options = t.options;
  const std::vector<int>& minima = coarse.minima;
  double gain_radius = t.Radius(t.coarse_nodes[minima.front()]);
  if (options.normalize_gain) refinement->EqualiseGain(gain_radius);

  Minimum best = refinement->Refine(t.coarse_nodes[minima.front()]);
  // A second basin of similar coarse loss (e.g. the other sign) is refined
  // too: the windowed coarse loss is only an approximation.
  for (size_t i = 1; i < minima.size() && i < 3; ++i) {
    const double r = t.Radius(t.coarse_nodes[minima[i]]);
    if (r >= t.Radius(best.lo) - 1 && r <= t.Radius(best.hi) + 1) continue;
    if (coarse.loss[minima[i]] - coarse.min > 0.1 * (coarse.max - coarse.min)) {
      break;
    }
    const Minimum other =
        refinement->Refine(t.coarse_nodes[minima[i]]);  // same gain
    if (other.corrected < best.corrected) best = other;
    break;
  }
  // Gain at the refined estimate if it moved much from where the gain was
  // computed.
  for (int round = 0; round < 3 && options.normalize_gain &&
                      std::abs(best.radius - gain_radius) > 0.1;
       ++round) {
    gain_radius = best.radius;
    refinement->EqualiseGain(gain_radius);
    refinement->ResetEvaluations();
    best = refinement->Refine(refinement->NearestNode(gain_radius));
  }
  return best;
}

// In focus unless the data say otherwise. Blurs near focus change the
// kernels little, so the loss is flat there (exactly flat inside the
// disk's in-focus threshold) and noise alone picks a minimum somewhere on
// or just beyond the plateau. Keep r = 0 unless the improvement over it
// exceeds 3 standard deviations of what noise alone gives: the loss
// difference between kernels h and h0 = h(0) has a noise term
// 2 <e(0), n * (h - h0)> / M with std ~ 2 sigma^2 sqrt(a(0) D / M),
// D = |h_l - h0_l|^2 + |h_r - h0_r|^2.
void PreferInFocus(const BlurTables& t,
                   double sigma2,
                   BlurRefinement* refinement,
                   Minimum* best) {
  const double inv_m = 1.0 / t.num_interior;
  if (best->radius != 0 && std::isfinite(sigma2) && sigma2 > 0) {
    const int zero = t.half_nodes;
    refinement->Evaluate(zero);
    const double zero_corrected =
        refinement->RawLoss(zero) - sigma2 * t.noise_gain[zero];
    const double pos = best->radius / t.step + t.half_nodes;
    const int n0 = std::min(t.num_nodes - 2, static_cast<int>(pos));
    const double s = pos - n0;
    const std::array<double, 3>& q = t.in_focus_distance[n0];
    const double d = q[0] + 2 * s * q[1] + s * s * q[2];
    const double threshold =
        3 * 2 * sigma2 * std::sqrt(t.noise_gain[zero] * d * inv_m);
    if (zero_corrected - best->corrected <= threshold) {
      best->radius = 0;
      best->corrected = zero_corrected;
      best->raw = refinement->RawLoss(zero);
    }
  }
}

// The corrected loss relative to the signal power of the interior:
// gain-equalised variances minus noise.
double RelativeResidual(const BlurTables& t,
                        const BlurRefinement& refinement,
                        double sigma2,
                        const Minimum& best) {
  const cv::Mat il = refinement.Left()(t.interior),
                ir = refinement.Right()(t.interior);
  cv::Scalar ml, sl, mr, sr;
  cv::meanStdDev(il, ml, sl);
  cv::meanStdDev(ir, mr, sr);
  const double noise2 = std::isfinite(sigma2) ? sigma2 : 0.0;
  const double power =
      std::max(sl[0] * sl[0] + sr[0] * sr[0] - 2 * noise2, 1e-300);
  return std::max(best.corrected, 0.0) / power;
}

// Rise of the exact corrected loss fit_quality_offset_px away from the
// minimum (weaker side).
double RiseAwayFromMinimum(const BlurTables& t,
                           double sigma2,
                           const Minimum& best,
                           BlurRefinement* refinement) {
  const int offset_nodes = std::max(
      1,
      static_cast<int>(std::round(t.options.fit_quality_offset_px / t.step)));
  const double node_pos = best.radius / t.step + t.half_nodes;
  double rise = kInf;
  for (const int side : {-1, 1}) {
    const int n = static_cast<int>(std::round(node_pos)) + side * offset_nodes;
    if (n < 0 || n >= t.num_nodes) continue;
    refinement->Evaluate(n);
    rise = std::min(
        rise,
        refinement->RawLoss(n) - sigma2 * t.noise_gain[n] - best.corrected);
  }
  return rise;
}

// The coarse search's index of least loss on the other sign of `radius`
// (-1: none, or radius 0).
int OppositeSignIndex(const BlurTables& t,
                      const CoarseCurve& coarse,
                      double radius) {
  int index = -1;
  for (size_t i = 0; i < coarse.loss.size(); ++i) {
    if (t.Radius(t.coarse_nodes[i]) * radius < 0 &&
        (index < 0 || coarse.loss[i] < coarse.loss[index])) {
      index = static_cast<int>(i);
    }
  }
  return index;
}

// Sign ambiguity: the best coarse loss on the other sign (at `opposite`,
// OppositeSignIndex), against the coarse loss at the estimate (limits the
// rise; sets opposite_sign_loss).
void CompareOppositeSign(const BlurTables& t,
                         const CoarseCurve& coarse,
                         const Minimum& best,
                         int opposite,
                         double* rise,
                         PatchBlurEstimate* result) {
  double here = kInf;
  for (size_t i = 0; i < coarse.loss.size(); ++i) {
    const double r = t.Radius(t.coarse_nodes[i]);
    if (std::abs(r - best.radius) <= 0.5 * t.options.coarse_step_px + 1e-9) {
      here = std::min(here, coarse.loss[i]);
    }
  }
  const double opposite_loss = opposite >= 0 ? coarse.loss[opposite] : kInf;
  result->opposite_sign_loss = opposite_loss;
  if (std::isfinite(opposite_loss) && std::isfinite(here)) {
    *rise = std::min(*rise, opposite_loss - here);
  }
}

}  // namespace

bool BlurEstimationOptions::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(max_radius_px) && max_radius_px >= 1,
                           max_radius_px);
  DPSFM_CHECK_OPTION_VALUE(
      std::isfinite(grid_step_px) && grid_step_px > 0 && grid_step_px <= 1,
      grid_step_px);
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(coarse_step_px) &&
                               coarse_step_px >= grid_step_px &&
                               coarse_step_px <= max_radius_px,
                           coarse_step_px);
  // The coarse nodes are nodes of the kernel grid.
  const double ratio = coarse_step_px / grid_step_px;
  DPSFM_CHECK_OPTION_VALUE(std::abs(ratio - std::round(ratio)) <= 1e-9 * ratio,
                           coarse_step_px);
  DPSFM_CHECK_OPTION_VALUE(coarse_band > 0 && coarse_band <= 1, coarse_band);
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(min_texture) && min_texture >= 0,
                           min_texture);
  DPSFM_CHECK_OPTION_VALUE(min_fit_quality >= 0 && min_fit_quality <= 1,
                           min_fit_quality);
  DPSFM_CHECK_OPTION_VALUE(
      fit_quality_offset_px > 0 && fit_quality_offset_px < max_radius_px,
      fit_quality_offset_px);
  DPSFM_CHECK_OPTION_GE(max_refinement_evaluations, 3);
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(min_evidence_z) && min_evidence_z >= 0,
                           min_evidence_z);
  return true;
}

PatchBlurEstimate PatchBlurEstimator::Estimate(const cv::Mat& left,
                                               const cv::Mat& right) const {
  return Estimate(Prepare(left, right));
}

PreparedBlurPatch PatchBlurEstimator::Prepare(const cv::Mat& left,
                                              const cv::Mat& right) const {
  const BlurTables& t = *tables_;
  const BlurEstimationOptions& options = t.options;
  DPSFM_CHECK(left.type() == CV_32FC1 && right.type() == CV_32FC1)
      << "DP patches must be CV_32FC1";
  DPSFM_CHECK(left.size() == t.patch_size && right.size() == t.patch_size)
      << "DP patches must be " << t.patch_size.width << "x"
      << t.patch_size.height << ", got " << left.cols << "x" << left.rows
      << " and " << right.cols << "x" << right.rows;

  PreparedBlurPatch patch;
  patch.patch_size = t.patch_size;
  patch.dft_size = t.dft_size;
  PatchBlurEstimate& result = patch.early;
  result.opposite_sign_loss = kInf;
  if (!AllFinite(left) || !AllFinite(right)) {
    result.reject_reason = "non-finite pixels";
    return patch;
  }
  result.texture = ViewsTexture(left, right);
  if (!(result.texture > options.min_texture) || result.texture <= 0) {
    result.reject_reason = "no horizontal texture";
    return patch;
  }
  EqualisedViews views;
  if (!EqualiseViews(left, right, options, &views)) {
    result.reject_reason = "view too dark for gain equalisation";
    return patch;
  }
  patch.gl = views.gl;
  patch.gr = views.gr;
  patch.offset = views.offset;
  if (options.normalize_gain) {
    patch.integral_left =
        BlurRefinement::PositiveIntegral(views.gl, views.offset);
    patch.integral_right =
        BlurRefinement::PositiveIntegral(views.gr, views.offset);
  }
  patch.sigma2_hp = PatchNoiseVariance(views.gl, views.gr, options);
  patch.coarse_band_terms = internal::CoarseBandTerms(t, views.gl, views.gr);
  return patch;
}

PatchBlurEstimate PatchBlurEstimator::Estimate(
    const PreparedBlurPatch& patch) const {
  const BlurTables& t = *tables_;
  const BlurEstimationOptions& options = t.options;
  DPSFM_CHECK(patch.patch_size == t.patch_size && patch.dft_size == t.dft_size)
      << "a patch prepared for " << patch.patch_size.width << "x"
      << patch.patch_size.height << " crops, searched as " << t.patch_size.width
      << "x" << t.patch_size.height;
  PatchBlurEstimate result = patch.early;
  if (!result.reject_reason.empty()) return result;
  const double sigma2_hp = patch.sigma2_hp;
  const CoarseCurve coarse =
      internal::CoarseSearch(t, patch.coarse_band_terms, sigma2_hp);

  // ---- Exact refinement. ----
  BlurRefinement refinement(t,
                            patch.gl,
                            patch.gr,
                            patch.offset,
                            sigma2_hp,
                            patch.integral_left,
                            patch.integral_right);
  Minimum best = RefineCoarseMinima(t, coarse, &refinement);
  // Final values with the final noise estimate.
  const double sigma2 = refinement.CurrentSigma2();
  best = refinement.Minimise(best.lo, best.hi, sigma2);
  PreferInFocus(t, sigma2, &refinement, &best);

  result.relative_residual = RelativeResidual(t, refinement, sigma2, best);
  result.radius_px = best.radius;
  result.loss = best.raw;
  result.corrected_loss = best.corrected;
  result.noise_sigma =
      std::isfinite(sigma2_hp) ? std::sqrt(sigma2_hp) : std::sqrt(sigma2);

  // Fit quality: the rise of the loss away from the minimum against the
  // residual at the minimum.
  double rise = RiseAwayFromMinimum(t, sigma2, best, &refinement);
  const int opposite = OppositeSignIndex(t, coarse, best.radius);
  if (best.radius != 0) {
    CompareOppositeSign(t, coarse, best, opposite, &rise, &result);
  }
  const double residual = std::max(best.raw, 1e-300);
  result.fit_quality =
      std::isfinite(rise) && rise > 0 ? rise / (rise + residual) : 0.0;
  result.fit_quality = std::min(1.0, std::max(1e-6, result.fit_quality));

  result.at_bound = std::abs(best.radius) > t.bound - 0.5 * t.step;
  internal::WeighBlurEvidence(t,
                              sigma2,
                              best,
                              opposite >= 0 ? t.coarse_nodes[opposite] : -1,
                              &refinement,
                              &result);
  if (result.evidence == BlurEvidence::kBeyondBound) {
    result.reject_reason = kBlurAtSearchBound;
    return result;
  }
  if (result.evidence == BlurEvidence::kUndetermined) {
    result.reject_reason = kBlurUndetermined;
    return result;
  }
  if (result.fit_quality < options.min_fit_quality) {
    result.reject_reason = "fit quality below threshold";
    return result;
  }
  result.valid = true;
  return result;
}

PatchBlurEstimate EstimatePatchBlur(const cv::Mat& left,
                                    const cv::Mat& right,
                                    const DPPsfModel& psf,
                                    const BlurEstimationOptions& options) {
  DPSFM_CHECK_OPTIONS(options, "BlurEstimationOptions");
  DPSFM_CHECK(left.size() == right.size())
      << "left and right patches differ in size";
  // One estimator per call: its tables cost tens of ms, so a caller with
  // many patches holds a PatchBlurEstimator instead (as the scale estimator
  // does); nothing is cached behind the caller's back.
  return PatchBlurEstimator(psf, options, left.size()).Estimate(left, right);
}

cv::Mat ToLuma(const cv::Mat& image) {
  if (image.channels() == 1) return image;
  cv::Mat gray;
  cv::transform(image, gray, cv::Matx13f(0.299f, 0.587f, 0.114f));
  return gray;
}

}  // namespace dpsfm
