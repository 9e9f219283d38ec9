// Intensity-based optimisation of the scale (paper sec. "Intensity-based
// Optimization", eq. (loss_refine)): with the focus distances g_i' fixed from
// the linear stage, a discrete search over candidate scales around s* of the
// cross-view alignment loss of the selected patches, then a finer second pass
// around the minimum and a bootstrap confidence interval.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/core/optics/dp_psf.h"
#include "dpsfm/core/optics/lens_model.h"

namespace dpsfm {

// What the loss compares (see IntensitySearchOptions::loss).
enum class IntensityLoss {
  // Eq. (loss_refine) verbatim: sum over channels of the L1 distance of the
  // per-patch normalised cross-blurred patches, eta(X) = X / ||X||_1.
  kPaperL1,
  // Squared distance of the same normalised patches (scaled to mean 1).
  kL2,
  // kL2 minus its expected sensor-noise floor. The cross-blurred noise has
  // energy sigma^2 ||H||^2 per pixel, which falls as the kernels grow, so an
  // uncorrected loss prefers larger blur (smaller s) on noisy data; this
  // removes that bias (docs/method.md, "Intensity stage").
  kNoiseCorrectedL2,
  // The default. Per channel, kNoiseCorrectedL2 divided by the signal power
  // of the two normalised cross-blurred patches (their variances) at the
  // patch's radius under the initial scale (fixed per patch, so the
  // denominator does not favour any candidate): the share of the patch's
  // structure the two views disagree on, averaged over the channels whose
  // structure rises above their noise (a channel without scene content is
  // skipped). The noise floor uses the pair estimate tightened by the fit
  // (as in the blur estimator). Each patch's curve then enters the sum as
  // d / (d + robust_loss_scale), d = its loss above its own minimum, so that
  // no patch can contribute more than 1. Why: the absolute losses above fall
  // as the kernels grow (heavy blur flattens both sides), so their plain sum
  // over many patches drifts to the small-s edge of the range as soon as
  // some patches do not fit (blur beyond the crops' support, depth varying
  // inside, a dead colour channel): the example scenes went to s* x 0.2.
  kRelativeL2,
};
const char* IntensityLossName(IntensityLoss loss);

struct IntensitySearchOptions {
  // Candidates uniformly spanning s* (1 +- T_s): the paper's 100 and 80 %.
  int num_candidates = 100;
  double relative_range = 0.8;  // T_s
  // Second pass: this many candidates uniformly between the neighbours of the
  // first pass's minimum (0 disables it).
  int num_refine_candidates = 24;
  IntensityLoss loss = IntensityLoss::kRelativeL2;
  // kRelativeL2 only: each patch contributes d / (d + c), d = its loss above
  // its own minimum over the candidates, c this value (a share of the
  // patch's structure left unexplained). Small c: robust to patches the
  // model does not fit; large c: closer to the plain sum.
  double robust_loss_scale = 0.01;
  // Spacing in px of the kernel grid the L2-family losses are evaluated on
  // (DPKernelGrid: kernels interpolated linearly in r between nodes, so a
  // patch is reduced once to inner products at the nodes its candidates
  // reach and every candidate then costs O(channels), not a convolution;
  // the blur search uses the same grid). 0 = the model's exact kernels at
  // every candidate radius (the slow reference path; kPaperL1 always uses
  // it).
  double grid_step_px = 0.25;
  // Blur radii are clamped to this (px); also never beyond what a patch's
  // border supports.
  double max_radius_px = 20;
  // Bootstrap resamples (views, then patches inside them) of the per-patch
  // loss curves for the confidence interval; 0 disables it.
  int num_bootstrap = 300;
  double confidence_level = 0.95;
  uint64_t seed = 42;
  // OpenMP threads; -1 = all.
  int num_threads = -1;
  bool Check(std::string* failure = nullptr) const;
};

// Geometry of a view as the search sees it.
struct IntensityView {
  DPLensData lens;
  double pixel_pitch_mm = 0;        // pitch of the patch pixels (after resize)
  double focus_distance_model = 0;  // g_i' (model units), fixed
};

// One selected patch with its crops.
struct IntensityPatch {
  int view = 0;      // index into the IntensityView list
  double depth = 0;  // z' (model units)
  // Left/right crops, same size, CV_32FC1/3 in [0,1] or CV_16UC1/3 (65535 =
  // 1). The loss is evaluated on the interior that excludes `border` pixels
  // on each side; the border feeds the convolution.
  cv::Mat left, right;
  int border = 0;
  // This patch's DP PSF when it differs from the search's (a profile that
  // changes across the frame); null = the search's.
  const DPPsfModel* psf = nullptr;
};

struct IntensitySearchResult {
  bool success = false;
  std::string failure_reason;
  double scale = 0;  // minimiser (parabolic refinement on the final grid)
  double scale_ci_low = 0, scale_ci_high = 0;
  // The whole loss curve (first and second pass merged, sorted by scale).
  std::vector<double> candidate_scales, candidate_losses;
  // The minimum lies on the first or last first-pass candidate: the true
  // minimiser may be outside the searched range.
  bool at_boundary = false;
  // Fraction of bootstrap resamples whose minimum lies within one first-pass
  // step of `scale` (1 = the curve is decisive).
  double bootstrap_support = 0;
  int num_patches = 0;
  int num_evaluations = 0;  // patch x candidate loss evaluations
  // Loss evaluations that threw (a patch whose loss cannot be evaluated at
  // a radius contributes nothing there); the report shows the count.
  int num_failed_evaluations = 0;
  // Node statistics (per patch and grid node) taken from the cache and
  // computed from the crops.
  int num_nodes_reused = 0, num_nodes_computed = 0;
};

// Loss of one patch at one signed blur radius (clamped as in the search).
// `noise_sigma_left/right` (per channel, may be empty = 0) feed
// kNoiseCorrectedL2 only.
double PatchAlignmentLoss(const IntensityPatch& patch,
                          double radius_px,
                          const DPPsfModel& psf,
                          IntensityLoss loss,
                          double max_radius_px,
                          const std::vector<double>& noise_sigma_left = {},
                          const std::vector<double>& noise_sigma_right = {});

// Robust sensor-noise sigma of an image (per channel): MAD of the response to
// the 3x3 mask [1 -2 1; -2 4 -2; 1 -2 1] (zero on planes and ramps, so mild
// defocused texture barely leaks in), divided by the mask's norm 6. Sharp
// texture inflates it.
std::vector<double> EstimateChannelNoiseSigma(const cv::Mat& image);

// Per-view noise sigma of a DP pair (per channel), from the same estimator
// applied to (left - right) / sqrt(2) after equalising the two means. The
// scene cancels where it matters: in focus the views are nearly equal, out
// of focus both are smooth; what is left is the noise of one view (assuming
// independent noise of equal strength in the two views).
std::vector<double> EstimatePairNoiseSigma(const cv::Mat& left,
                                           const cv::Mat& right);

// What one SearchScaleByIntensity keeps for the next over the same crops
// (the view budget's checkpoints search the stored crops of the views they
// share again): each crop's noise estimate and kernel-grid node statistics,
// with the grids they were taken on. A statistic depends on nothing but the
// crop and its grid's kernels, so a later search takes it where it would
// compute it and answers the same, to the bit. A crop is known by its
// pixels (compared byte for byte), its border and its grid; a grid is
// reused only where its kernels equal the new search's. Holds what the last
// search used; one search at a time.
class IntensityStatsCache {
 public:
  IntensityStatsCache();
  ~IntensityStatsCache();
  IntensityStatsCache(const IntensityStatsCache&) = delete;
  IntensityStatsCache& operator=(const IntensityStatsCache&) = delete;

  // Crops held (the last search's counts are in its result).
  int NumCrops() const;

  struct Impl;  // intensity_loss.h
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

// The search. `initial_scale` is s*; views carry g_i' from the linear stage.
// Never throws on bad data: success = false with a reason. `cache`
// (optional) carries statistics from one search to the next.
IntensitySearchResult SearchScaleByIntensity(
    const std::vector<IntensityView>& views,
    const std::vector<IntensityPatch>& patches,
    double initial_scale,
    const DPPsfModel& psf,
    const IntensitySearchOptions& options,
    IntensityStatsCache* cache = nullptr);

}  // namespace dpsfm
