// Which patches of a view are searched and which are kept (steps of
// DPScaleEstimator::AddView between the patch grid and the crop store):
// screening by texture against noise, the blur-search share, and why a
// searched patch is not usable.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/blur/patch_grid.h"

namespace dpsfm {

// Patch rejection reasons that more than one step reports.
extern const char* const kTextureTooWeak;
extern const char* const kLeftUnsearched;
extern const char* const kNotFittedByOneBlur;

// A patch's confidence: texture x fit quality / (relative depth variance +
// 1e-4). The reference code's sobel * exp(-1e6 loss) / (var(depth) + 1e-10),
// with the blur estimator's fit quality in place of exp(-1e6 loss) (which
// underflows at real noise levels) and the RELATIVE depth variance (scale
// free) floored at 1 % std, so that depth noise below that level does not
// decide the ranking. Negative texture or fit quality count as 0.
double PatchConfidence(double texture,
                       double fit_quality,
                       double relative_depth_variance);

// Top-T_c selection by confidence, per view.
// Indices of the `fraction` highest `confidence` values (ties by index), at
// least min(min_count, n) of them. Non-finite confidences rank last.
std::vector<int> SelectTopFraction(const std::vector<double>& confidence,
                                   double fraction,
                                   int min_count);

// The same count as SelectTopFraction, spread over depth: `key` (e.g. inverse
// depth, which blur is affine in) is cut into `strata` equal-width bins and
// the count is shared evenly among the non-empty bins (best confidence first
// inside each; what a bin cannot fill goes to the best remaining patches).
// Pure top-T_c picks the most textured plane of a view again and again,
// which leaves the view's own solve without depth variation; the linear
// system needs blur range, the paper's T_p test says as much.
// strata <= 1 is SelectTopFraction.
std::vector<int> SelectTopFractionStratified(
    const std::vector<double>& confidence,
    const std::vector<double>& key,
    double fraction,
    int min_count,
    int strata);

struct ScreenedPatches {
  std::vector<int> index;  // candidates that pass, in grid order
  // Per passing candidate: PatchConfidence with a fit quality of 1 (its
  // largest), so an upper bound of the final confidence; and the inverse
  // median depth (for the depth strata).
  std::vector<double> confidence;
  std::vector<double> inverse_depth;
};

// Screening, cheap and on every candidate with depth: the texture of its
// crop (`crop_border` px around the interior) goes into (*estimates)[k]; a
// patch whose texture SNR falls below 0.9 min_texture_snr (what the search
// would drop anyway, with a margin for its gain equalisation) gets
// kTextureTooWeak and its noise. A patch that passes gets its noise from
// its search (PatchScreening::NoiseSigmaBound settles most without it).
// threads: OpenMP threads (-1: all).
ScreenedPatches ScreenPatches(const cv::Mat& gray_left,
                              const cv::Mat& gray_right,
                              const std::vector<PatchCandidate>& candidates,
                              int crop_border,
                              double min_texture_snr,
                              int threads,
                              std::vector<PatchBlurEstimate>* estimates);

struct SearchShareOptions {
  // The share searched is blur_search_factor x top_patch_fraction of the
  // screened patches (at least blur_search_factor x min_patches_per_view),
  // spread over depth_strata depth strata; 0 or a share >= 1 searches all.
  double blur_search_factor = 3;
  double top_patch_fraction = 0.1;
  int min_patches_per_view = 8;
  int depth_strata = 4;
};

// Which candidates the blur search runs on (1 per candidate). The paper
// searches all and keeps the top T_c by confidence; since a patch's
// confidence never exceeds its screening confidence, searching the best
// share by screening confidence finds the same kind of patches at a
// fraction of the cost. Screened patches left out get kLeftUnsearched.
std::vector<char> ChooseSearchedPatches(
    const ScreenedPatches& screened,
    int num_candidates,
    const SearchShareOptions& options,
    std::vector<PatchBlurEstimate>* estimates);

// The view's residual threshold: max(max_relative_residual, factor x the
// median relative residual of the valid searched patches).
double ViewResidualThreshold(const std::vector<PatchCandidate>& candidates,
                             const std::vector<PatchBlurEstimate>& estimates,
                             double max_relative_residual,
                             double relative_residual_factor);

// Why a patch is not usable, "" if it is: rejected before the search, no
// valid blur estimate (the estimator's reason), texture too weak for the
// noise, or not fitted by one blur (relative residual over the threshold).
std::string PatchRejection(const PatchCandidate& candidate,
                           const PatchBlurEstimate& estimate,
                           double min_texture_snr,
                           double residual_threshold);

}  // namespace dpsfm
