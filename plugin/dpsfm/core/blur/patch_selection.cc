#include "dpsfm/core/blur/patch_selection.h"

#include <algorithm>
#include <cmath>

#include "dpsfm/core/scale/linear_estimator.h"
#include "dpsfm/core/util/statistics.h"
#include "dpsfm/core/util/threads.h"

namespace dpsfm {

const char* const kTextureTooWeak = "with texture too weak for the noise";
const char* const kLeftUnsearched =
    "left unsearched (ranked below the blur-search share by texture and "
    "depth flatness)";
const char* const kNotFittedByOneBlur =
    "not fitted by one blur (blur beyond the search bound or depth varying "
    "inside)";

ScreenedPatches ScreenPatches(const cv::Mat& gray_left,
                              const cv::Mat& gray_right,
                              const std::vector<PatchCandidate>& candidates,
                              int crop_border,
                              double min_texture_snr,
                              int threads,
                              std::vector<PatchBlurEstimate>* estimates) {
  ScreenedPatches out;
  const int num = static_cast<int>(candidates.size());
  const PatchScreening screening(gray_left, gray_right);
  std::vector<char> pass(num, 0);
#ifdef _OPENMP
  threads = EffectiveNumThreads(threads);
#pragma omp parallel for num_threads(threads) schedule(dynamic)
#endif
  for (int k = 0; k < num; ++k) {
    if (!candidates[k].reject.empty()) continue;
    const cv::Rect r = PatchCrop(candidates[k].interior, crop_border);
    PatchBlurEstimate& e = (*estimates)[k];
    e.texture = screening.Texture(r);
    e.noise_sigma = screening.NoiseSigma(r);
    if (min_texture_snr > 0 &&
        TextureSnr(e.texture, e.noise_sigma) < 0.9 * min_texture_snr) {
      e.reject_reason = kTextureTooWeak;
      continue;
    }
    pass[k] = 1;
  }
  for (int k = 0; k < num; ++k) {
    if (!pass[k]) continue;
    out.index.push_back(k);
    out.confidence.push_back((*estimates)[k].texture /
                             (candidates[k].depth.relative_variance + 1e-4));
    out.inverse_depth.push_back(1.0 / candidates[k].depth.median);
  }
  return out;
}

std::vector<char> ChooseSearchedPatches(
    const ScreenedPatches& screened,
    int num_candidates,
    const SearchShareOptions& options,
    std::vector<PatchBlurEstimate>* estimates) {
  std::vector<char> search(num_candidates, 0);
  if (screened.index.empty()) return search;
  const double share = options.blur_search_factor * options.top_patch_fraction;
  std::vector<int> chosen;
  if (options.blur_search_factor > 0 && share < 1) {
    chosen = SelectTopFractionStratified(
        screened.confidence,
        screened.inverse_depth,
        share,
        static_cast<int>(std::ceil(options.blur_search_factor *
                                   options.min_patches_per_view)),
        options.depth_strata);
  } else {
    chosen.resize(screened.index.size());
    for (size_t i = 0; i < chosen.size(); ++i) {
      chosen[i] = static_cast<int>(i);
    }
  }
  for (int i : chosen) search[screened.index[i]] = 1;
  for (int k : screened.index) {
    if (!search[k]) (*estimates)[k].reject_reason = kLeftUnsearched;
  }
  return search;
}

double ViewResidualThreshold(const std::vector<PatchCandidate>& candidates,
                             const std::vector<PatchBlurEstimate>& estimates,
                             double max_relative_residual,
                             double relative_residual_factor) {
  std::vector<double> residuals;
  for (size_t k = 0; k < candidates.size(); ++k) {
    if (candidates[k].reject.empty() && estimates[k].valid &&
        std::isfinite(estimates[k].relative_residual)) {
      residuals.push_back(estimates[k].relative_residual);
    }
  }
  if (residuals.empty()) return max_relative_residual;
  return std::max(max_relative_residual,
                  relative_residual_factor * UpperMedianInPlace(&residuals));
}

std::string PatchRejection(const PatchCandidate& candidate,
                           const PatchBlurEstimate& e,
                           double min_texture_snr,
                           double residual_threshold) {
  if (!candidate.reject.empty()) return candidate.reject;
  if (!e.valid || e.at_bound || !std::isfinite(e.radius_px)) {
    return e.reject_reason.empty() ? "with no blur estimate" : e.reject_reason;
  }
  if (!(TextureSnr(e.texture, e.noise_sigma) >= min_texture_snr)) {
    return kTextureTooWeak;
  }
  if (e.relative_residual > residual_threshold) return kNotFittedByOneBlur;
  return "";
}

}  // namespace dpsfm
