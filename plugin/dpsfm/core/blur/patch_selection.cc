#include "dpsfm/core/blur/patch_selection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "dpsfm/core/util/check.h"
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

double PatchConfidence(double texture,
                       double fit_quality,
                       double relative_depth_variance) {
  return std::max(texture, 0.0) * std::max(fit_quality, 0.0) /
         (relative_depth_variance + 1e-4);
}

std::vector<int> SelectTopFraction(const std::vector<double>& confidence,
                                   double fraction,
                                   int min_count) {
  DPSFM_CHECK(fraction > 0 && fraction <= 1) << "fraction " << fraction;
  const int n = static_cast<int>(confidence.size());
  int count = static_cast<int>(std::ceil(fraction * n - 1e-9));
  count = std::min(n, std::max(count, min_count));
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  auto key = [&](int i) {
    return std::isfinite(confidence[i])
               ? confidence[i]
               : -std::numeric_limits<double>::infinity();
  };
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return key(a) > key(b);
  });
  order.resize(count);
  std::sort(order.begin(), order.end());
  return order;
}

std::vector<int> SelectTopFractionStratified(
    const std::vector<double>& confidence,
    const std::vector<double>& key,
    double fraction,
    int min_count,
    int strata) {
  DPSFM_CHECK_EQ(confidence.size(), key.size());
  if (strata <= 1) return SelectTopFraction(confidence, fraction, min_count);
  const int n = static_cast<int>(confidence.size());
  const int count = static_cast<int>(
      SelectTopFraction(confidence, fraction, min_count).size());
  if (count == 0) return {};
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (double k : key) {
    if (std::isfinite(k)) {
      lo = std::min(lo, k);
      hi = std::max(hi, k);
    }
  }
  auto conf = [&](int i) {
    return std::isfinite(confidence[i])
               ? confidence[i]
               : -std::numeric_limits<double>::infinity();
  };
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return conf(a) > conf(b);
  });
  std::vector<std::vector<int>> bins(strata);
  for (int i : order) {
    if (!std::isfinite(key[i])) continue;
    const int b =
        hi > lo ? std::min(strata - 1,
                           static_cast<int>((key[i] - lo) / (hi - lo) * strata))
                : 0;
    bins[b].push_back(i);
  }
  int nonempty = 0;
  for (const auto& b : bins) nonempty += !b.empty();
  std::vector<bool> taken(n, false);
  int num_taken = 0;
  // Round-robin over the bins, best first inside each, up to an even share.
  const int share = nonempty > 0 ? count / nonempty : 0;
  for (const auto& b : bins) {
    for (int q = 0; q < std::min<int>(share, b.size()); ++q) {
      taken[b[q]] = true;
      ++num_taken;
    }
  }
  for (int i : order) {
    if (num_taken >= count) break;
    if (!taken[i]) {
      taken[i] = true;
      ++num_taken;
    }
  }
  std::vector<int> selected;
  for (int i = 0; i < n; ++i) {
    if (taken[i]) selected.push_back(i);
  }
  return selected;
}

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
  ParallelFor(num, threads, [&](int k) {
    if (!candidates[k].reject.empty()) return;
    const cv::Rect r = PatchCrop(candidates[k].interior, crop_border);
    PatchBlurEstimate& e = (*estimates)[k];
    e.texture = screening.Texture(r);
    // TextureSnr falls as the noise grows, so a texture that clears the
    // threshold over the noise's upper bound clears it over the noise: the
    // views' own noise estimates (two of three medians) are needed only
    // where the bound does not settle it.
    const double threshold = 0.9 * min_texture_snr;
    if (min_texture_snr > 0 &&
        !(TextureSnr(e.texture, screening.NoiseSigmaBound(r)) >= threshold)) {
      e.noise_sigma = screening.NoiseSigma(r);
      if (TextureSnr(e.texture, e.noise_sigma) < threshold) {
        e.reject_reason = kTextureTooWeak;
        return;
      }
    }
    pass[k] = 1;
  });
  for (int k = 0; k < num; ++k) {
    if (!pass[k]) continue;
    out.index.push_back(k);
    out.confidence.push_back(PatchConfidence(
        (*estimates)[k].texture, 1.0, candidates[k].depth.relative_variance));
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
