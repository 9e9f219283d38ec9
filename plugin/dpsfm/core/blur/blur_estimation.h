// Per-patch DP blur estimation (Punnappurath et al., ICCP 2020; paper eq.
// loss_modeling): the signed blur radius r of a patch of constant depth
// minimises the cross-view loss
//
//   L(r) = mean over the patch interior of (G_l * H_r(r) - G_r * H_l(r))^2,
//
// the left patch blurred by the right PSF against the right patch blurred by
// the left PSF. The PSFs come from a DPPsfModel only.
//
// How the search works, and why:
// - The loss is non-convex; on the wrong sign it keeps falling towards the
//   bound (heavy blur flattens both sides). So the search is global: the loss
//   is evaluated on a grid over [-max, max] in the frequency domain (one FFT
//   per view and patch, kernel spectra precomputed once per patch size,
//   Parseval, no inverse FFT), then refined with the exact spatial loss.
// - Refinement: kernels are precomputed on a grid of step grid_step_px and
//   interpolated linearly in r in between. The interpolated kernel's centroid
//   (the quantity DP disparity measures) is then exactly linear in r, the
//   residual is linear in r inside a grid interval and the loss quadratic, so
//   each interval's minimum is closed-form. A handful of inverse FFTs walk
//   from the coarse minimum downhill; the result resolves r far below 0.1 px.
// - Noise bias (docs/method.md, "Blur search"): with i.i.d. noise of std sigma
// on both
//   views the loss gains sigma^2 (|H_l|^2 + |H_r|^2), largest for the
//   sharpest kernels, so noise makes small blurs read large and in-focus
//   patches read ~0.5-0.7 px. The estimator subtracts that expected floor with
//   sigma estimated from the patch itself (see EstimatePatchBlur).
// - Left/right gain: real DP views differ in gain (vignetting differs between
//   the half apertures and across the frame). A gain mismatch leaves a
//   residual that only blurring both sides can shrink, which biases |r| up.
//   The views' whole-patch means are equalised first (for the coarse search);
//   then, since those means also differ because the views are shifted by
//   ~0.6 r, the gain is re-derived from the interior means of the two blurred
//   cross views at the current estimate (equal for equal gains) and the
//   refinement repeated while the estimate moves by > 0.1 px.
// - Near focus the loss is flat (exactly, for |r| <= 0.5 with the disk): the
//   estimate is 0 unless it beats r = 0 by more than 3 standard deviations of
//   the noise-only loss difference.
#pragma once

#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/core/optics/dp_psf.h"

namespace dpsfm {

// The reject reason of a patch whose blur lies beyond the search bound (its
// loss still falls into the bound by more than noise explains).
extern const char* const kBlurAtSearchBound;
// The reject reason of a patch whose loss curve does not determine a blur:
// no rise on both sides of its minimum (nor into the bound) beyond what the
// patch's noise gives.
extern const char* const kBlurUndetermined;

// What a patch's loss curve says about its blur, weighed against what noise
// alone gives for that patch (PatchBlurEstimate::evidence).
enum class BlurEvidence {
  // A minimum the data determine: the corrected loss rises on both sides of
  // it (and towards the other sign's best) by more than noise explains.
  kMeasured,
  // The minimum at the search bound, the loss still falling into it by more
  // than noise explains: the blur lies beyond the bound.
  kBeyondBound,
  // Neither: a flat or noise-shaped curve, or a minimum at the bound the
  // data do not pull there.
  kUndetermined,
};

struct BlurEstimationOptions {
  // Search bound on |r| in pixels of the (possibly resized) DP frame. 20 is
  // the reference DSLR default (kernel 41 on 0.5-resized Canon 5D IV frames);
  // the phone default is 10. Patches need a border of
  // psf.KernelRadius(max_radius_px) pixels around the interior the loss uses.
  double max_radius_px = 20;

  // Spacing in px of the kernel grid. Kernels are precomputed at multiples of
  // it and interpolated linearly in between, which keeps the kernel centroid
  // exact; 0.25 px keeps the remaining shape error well below 0.01 px of r.
  double grid_step_px = 0.25;

  // Spacing in px of the global (coarse, frequency-domain) search; a multiple
  // of grid_step_px. 0.5 px resolves the basin of the loss even for blurs
  // of a pixel, the refinement does the rest.
  double coarse_step_px = 0.5;

  // Fraction of the frequency band (per axis, of Nyquist) the coarse search
  // uses. The coarse search only has to find the basin; low frequencies
  // carry the DP shift for every |r| >= 1 and cost a quarter of the full
  // band. 1 = full band.
  double coarse_band = 0.5;

  // Equalise the two views' means before the loss (DP views differ in gain;
  // an uncorrected gain difference reads as extra blur).
  bool normalize_gain = true;

  // Subtract the loss's expected noise floor sigma^2 (|H_l|^2 + |H_r|^2) with
  // sigma estimated from the patch (without it, noise reads small blurs large;
  // docs/method.md, "Blur search").
  bool subtract_noise_floor = true;

  // Reject patches whose texture (mean |horizontal Sobel| of left + right,
  // intensities in [0, 1]) is below this. 0 rejects only exactly flat
  // patches; the pipeline ranks by texture and fit quality anyway.
  double min_texture = 0.0;

  // Reject patches whose fit_quality is below this. 0 = report everything
  // and let the caller rank; the value is a confidence, not a test.
  double min_fit_quality = 0.0;

  // Offset in px at which fit_quality compares the loss with its minimum
  // (about the precision the scale stage needs from a patch).
  double fit_quality_offset_px = 1.0;

  // Cap on exact loss evaluations (inverse FFTs) per basin in the refinement;
  // the walk usually needs 3-5.
  int max_refinement_evaluations = 24;

  // How many standard deviations of its noise a rise of the corrected loss
  // must reach to count as evidence (BlurEvidence): on each side of a
  // minimum for kMeasured, into the bound for kBeyondBound. The rise is
  // taken at 1, 2 and 4 px from the minimum, each against the noise of the
  // loss difference there.
  double min_evidence_z = 3.5;

  bool Check(std::string* failure = nullptr) const;
};

struct PatchBlurEstimate {
  // True if radius_px is a usable estimate; otherwise reject_reason says why.
  bool valid = false;
  // Signed blur radius in px (r > 0 farther than the focal plane). 0 when the
  // patch is indistinguishable from in focus.
  double radius_px = 0;
  // Cross-view loss at radius_px: mean squared difference over the interior
  // after gain equalisation, noise floor NOT subtracted (the reference code's
  // quantity).
  double loss = 0;
  // The same with the expected noise floor subtracted (what was minimised;
  // may be slightly negative).
  double corrected_loss = 0;
  // True if the minimum lies at the search bound (then valid is false).
  bool at_bound = false;
  // What the loss curve says (valid only when kMeasured).
  BlurEvidence evidence = BlurEvidence::kUndetermined;
  // Standard error of radius_px from the loss curve (px; +inf unless
  // kMeasured): the curve's curvature against the noise of its slope, the
  // residual at the minimum counted as noise where it exceeds the floor.
  double radius_se_px = std::numeric_limits<double>::infinity();
  // Significance of the weaker rise (in noise standard deviations): both
  // sides for a minimum inside the bound, the inner side at the bound.
  double evidence_z = 0;
  // Confidence in (0, 1], higher = better: C / (C + R) with C the rise of the
  // corrected loss fit_quality_offset_px away from the minimum (the weaker
  // side) and R the loss at the minimum. Near 1: the patch pins r well below
  // a pixel; near 0: flat loss (no texture) or a poor fit.
  double fit_quality = 0;
  // Mean |horizontal Sobel| (3x3, unnormalised) of left + right.
  double texture = 0;
  // Estimated noise std of one view in the patch's intensity units.
  double noise_sigma = 0;
  // Loss (corrected) of the best minimum on the opposite sign of radius_px,
  // from the coarse search; +inf if there is none. A small gap to
  // corrected_loss means an ambiguous sign.
  double opposite_sign_loss = 0;
  // corrected_loss relative to the interior's signal power (variance of
  // left + variance of right, gain-equalised, noise variance removed): the
  // share of the patch's structure the best kernel pair leaves unexplained.
  // ~0 for a patch the model fits (one depth, blur inside the bound); large
  // when the true blur lies beyond the search bound (then a spurious small
  // radius can win) or the depth varies inside the patch.
  double relative_residual = 0;
  std::string reject_reason;
};

// The part of a patch's search that does not depend on the PSF: its
// texture, the gain-equalised views, their noise and what the coarse search
// needs of their spectra. A caller that searches one patch with many
// profiles (the profile fit: one search per candidate profile) prepares it
// once (PatchBlurEstimator::Prepare) and passes it to estimators of the same
// options and patch size.
struct PreparedBlurPatch {
  // The texture; reject_reason set when the search ends before it starts
  // (non-finite pixels, no texture, too dark to equalise).
  PatchBlurEstimate early;
  cv::Mat gl, gr;  // the gain-equalised views minus `offset`
  double offset = 0;
  // With normalize_gain, the integral images of gl and gr + offset: every
  // search of the patch (one per profile in a profile fit) equalises the
  // gains on them first.
  cv::Mat integral_left, integral_right;
  double sigma2_hp = 0;  // the patch's noise variance (inf without a floor)
  std::vector<float> coarse_band_terms;
  cv::Size patch_size, dft_size;  // the geometry it was prepared for
};

namespace internal {
struct BlurTables;
}  // namespace internal

// Estimates patches of one size with one PSF model. Precomputes the kernel
// spectra once (tens of ms, tens of MB for 111 px patches at |r| <= 20);
// Estimate is const and thread-safe, so one instance serves all threads.
class PatchBlurEstimator {
 public:
  // The tables are built on num_threads threads (-1: all).
  PatchBlurEstimator(const DPPsfModel& psf,
                     const BlurEstimationOptions& options,
                     const cv::Size& patch_size,
                     int num_threads = 1);
  ~PatchBlurEstimator();

  // left/right: CV_32FC1, patch_size, intensities roughly [0, 1], including a
  // border of Border() pixels that the loss ignores.
  PatchBlurEstimate Estimate(const cv::Mat& left, const cv::Mat& right) const;

  // Estimate in two steps: what does not depend on the PSF, then the search
  // with this estimator's. `patch` must come from an estimator of the same
  // options and patch size (checked: its geometry).
  PreparedBlurPatch Prepare(const cv::Mat& left, const cv::Mat& right) const;
  PatchBlurEstimate Estimate(const PreparedBlurPatch& patch) const;

  // Width of the ignored border: psf.KernelRadius(max_radius_px).
  int Border() const;
  const cv::Size& PatchSize() const;
  const BlurEstimationOptions& Options() const;

 private:
  // Defined in blur_search_internal.h.
  std::unique_ptr<const internal::BlurTables> tables_;
};

// left/right: grayscale CV_32FC1 patches of equal size, intensities roughly
// [0, 1], INCLUDING a border of >= psf.KernelRadius(max_radius_px) that the
// loss ignores. Builds a PatchBlurEstimator for this one patch: for many
// patches, hold one PatchBlurEstimator and call its Estimate.
PatchBlurEstimate EstimatePatchBlur(const cv::Mat& left,
                                    const cv::Mat& right,
                                    const DPPsfModel& psf,
                                    const BlurEstimationOptions& options);

// The grey view the blur search works on: CV_32FC1 as is, CV_32FC3 by Rec.
// 601 weights in the channel order given (the loss is symmetric in it).
cv::Mat ToLuma(const cv::Mat& image);

// Screening patches before the blur search (patch_screening.cc).

// Mean |horizontal Sobel| (3x3, unnormalised, BORDER_REFLECT_101) of a
// CV_32FC1 patch: DP disparity is horizontal, so only vertical edges carry it.
double HorizontalTexture(const cv::Mat& gray_patch);

// Robust noise std of a CV_32FC1 patch from the median absolute response of
// the 3x3 Laplacian-like mask [1 -2 1; -2 4 -2; 1 -2 1] (Immerkaer 1996) over
// the patch without its outer pixel ring. Texture inflates it.
double EstimateNoiseSigma(const cv::Mat& gray_patch);
// Whether EstimateNoiseSigma(gray_patch) >= sigma, exactly (false for a NaN
// sigma), by counting the responses below the median that sigma needs
// instead of selecting it: the count PairNoiseVariance makes.
bool NoiseSigmaReaches(const cv::Mat& gray_patch, double sigma);
// The noise variance of two gain-equalised CV_32FC1 views of a patch: the
// smaller of the views' estimates (0.5 (sl^2 + sr^2), inflated by texture)
// and the difference's (sd^2, sd = EstimateNoiseSigma(gl - gr) / sqrt 2,
// inflated by DP disparity), the rule PatchScreening::NoiseSigma follows
// on its subsampled maps. Each view is filtered once.
double PairNoiseVariance(const cv::Mat& gl, const cv::Mat& gr);

// Cheap per-patch texture and noise measures for a whole view, computed once
// per view (not once per patch) to screen patches before the blur search:
// the horizontal texture of HorizontalTexture (|Sobel x| of left + right) by
// an integral image, and EstimateNoiseSigma's estimate from the mask's
// responses on left, right and left - right (the smallest per-view-sum
// estimate, as PatchBlurEstimator::Estimate takes), on every other pixel.
// Texture over what noise alone gives: for i.i.d. noise of std sigma per
// view, the horizontal Sobel of left + right has mean |.| = 3.91 sigma, so
// pure noise reads ~1.
double TextureSnr(double texture, double noise_sigma);

class PatchScreening {
 public:
  // Grey CV_32FC1 views of one size.
  PatchScreening(const cv::Mat& gray_left, const cv::Mat& gray_right);

  // Mean |horizontal Sobel| of left + right over `rect`.
  double Texture(const cv::Rect& rect) const;
  // Noise std of one view over `rect` (without its outer ring).
  double NoiseSigma(const cv::Rect& rect) const;
  // An upper bound of NoiseSigma(rect), to the bit (NoiseSigma is the
  // smaller of the views' estimate and this one, the difference view's),
  // at a third of its cost.
  double NoiseSigmaBound(const cv::Rect& rect) const;
  // TextureSnr of Texture(rect) and NoiseSigma(rect).
  double TextureSnr(const cv::Rect& rect) const;

 private:
  // The difference view's estimate, squared.
  double DifferenceVariance(const cv::Rect& rect) const;

  cv::Mat texture_integral_;                       // CV_64FC1
  cv::Mat noise_left_, noise_right_, noise_diff_;  // |responses|, CV_32FC1
};

// Patch geometry (patch_geometry.cc).

// Patch geometry on the working frame (the DP frame after resizing by
// resize_factor).
struct PatchGeometry {
  int patch_size;        // odd, px of the working frame
  int stride;            // px of the working frame
  double max_radius_px;  // search bound, px of the working frame
  double resize_factor;  // working frame = DP frame * resize_factor
};

// Defaults for a DP frame size. The search bound follows the reference code's
// anchors, DSLR 6720x4480 resized by 0.5 with |r| <= 20 and phone DP frames
// ~1512 px on the short side with |r| <= 10: at the reference resize (1/k,
// smallest integer k bringing the short side to <= 2800 px) it is
// interpolated linearly in the short side between the anchors (proportional
// beyond them), which fixes it in frame pixels. The working resolution is
// then 1/k with k = round(frame bound / 10 px) (at least 1): the coarsest
// reduction keeping the bound near the phone anchor's 10 px. So phone
// frames and frames up to ~1880 px on the short side keep their
// resolution, 3000x2000 is halved (|r| <= 8.5) and a 6720x4480 DSLR frame
// works at 1/4 (|r| <= 10), the reference's 0.5 cut in half again (the
// scale does not change: docs/benchmark.md). patch = 6 |r|max - 9
// (>= 2 |r|max + 21), stride = 2 |r|max + 7, which reproduce both anchors.
PatchGeometry DefaultPatchGeometry(const cv::Size& frame_size);
// The same with an explicit resize factor in (0, 1]: the bound is the same in
// frame pixels (so 0.5 on a 6720x4480 frame gives the reference's 111 / 47 /
// |r| <= 20).
PatchGeometry DefaultPatchGeometry(const cv::Size& frame_size,
                                   double resize_factor);
// The patch and stride that go with a radius bound (the rule above).
PatchGeometry PatchGeometryForRadius(double max_radius_px,
                                     double resize_factor);

}  // namespace dpsfm
