// Fitting the DP split profile (SplitProfilePsf along its path by centroid
// offset, SplitProfileParams::ForCentroidOffset) to data:
// the profile is the largest systematic error source on real sensors
// (docs/psf-profiles.md): a wrong one scales every recovered radius, and the
// scale inherits the factor.
//
// Two criteria, one search:
// - Self-calibration (radii unknown): for every candidate profile each
//   patch's blur is searched as usual and the relative residual at its best
//   radius is kept. The kernel pair's support (the disk, whatever the split)
//   and its centroid offset (the split) must both match the data for the
//   cross-view identity G_l * H_r = G_r * H_l to hold; a profile with the
//   wrong split fits only by trading one against the other, which leaves
//   structure unexplained. The profile minimising the robust mean residual
//   over patches with enough blur (>= 2 px: smaller kernels carry no shape)
//   is the fit. Measured on synthetic patches (noise 0.005): residual
//   minimum within a few % of the true split for sharper and softer splits,
//   crosstalk and rim softening, with recovered radii within ~2 %.
// - Calibration (radii known, e.g. a planar target at measured distances):
//   the profile whose recovered radii agree with the known ones in the
//   median; residuals are reported alongside.
// Self-calibration weighs the translating disk (the paper's model) against
// the best split profile by the same criterion and keeps it unless the
// profile fits better in 95 % of paired bootstrap resamples, so data made
// with it are not moved to a near neighbour.
// The fitted exponent carries a bootstrap interval (patches resampled), and
// the fit says when the data do not determine it (too few usable patches,
// minimum at the range's edge, interval too wide) so the caller can fall back
// to the translating disk and say why.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/optics/dp_psf.h"

namespace dpsfm {

struct ProfilePatch {
  // Grey CV_32FC1 crops of equal size, intensities ~[0, 1], including the
  // border PatchBlurEstimator needs for the options' max_radius_px.
  cv::Mat left, right;
  // Known signed blur radius (calibration); NaN = unknown (self-calibration).
  double known_radius_px = std::numeric_limits<double>::quiet_NaN();
  // Horizontal position of the patch centre in the frame, 0 (left edge) to
  // 1 (right edge): profiles change across the frame.
  double x_fraction = 0.5;
  double y_fraction = 0.5;  // vertical, 0 (top) to 1 (bottom)
};

struct SplitProfileFitOptions {
  // Search range along the family's path by centroid offset per radius
  // (SplitProfileParams::ForCentroidOffset): a log-spaced grid, then a
  // finer grid between the neighbours of the best node, then a parabola in
  // log kappa. The default spans what real DP sensors show (weak splits of
  // ~0.06 R to the Pixel 4's ~0.46 R, beyond the sharp half disk's 0.414 R
  // through a bright rim).
  double min_centroid_offset = 0.03;
  double max_centroid_offset = 0.47;
  // Coarse grid: min, min q, min q^2, ... up to max (GeometricNodes; q is
  // the spacing of 11 nodes over 0.03-0.414 R, the family's range before
  // its bright rim).
  double grid_ratio = 1.3002;
  int num_refine = 4;
  // Self-calibration: profiles whose criterion lies within this fraction
  // above the minimum count as consistent with the data (the criterion is
  // a residual of model misfit more than of noise: on a sensor outside the
  // family the minimum can sit tens of % of centroid offset away from the
  // truth while its neighbours fit almost as well).
  double consistency_tolerance = 0.1;
  // Patches with |r| below this (under the translating disk, or known) carry
  // no information on the profile's shape and are left out.
  double min_abs_radius_px = 2.0;
  // Self-calibration: the largest residuals are trimmed (depth edges,
  // occlusions, patches the model cannot fit whatever the profile).
  double trim_fraction = 0.5;
  int min_patches = 20;
  // Bootstrap over patches; the fit counts as determined when the 95 %
  // interval of the centroid offset per radius is narrower than this
  // fraction of it (each side).
  int num_bootstrap = 200;
  // Self-calibration keeps the translating disk unless the best split
  // profile's criterion is at least this factor lower (and lower in 95 % of
  // paired resamples). Measured: other profiles fit 5-70x better than the
  // translating disk; on translating-disk scenes the best profile is within
  // 0.5-1.1x (1.1x on slanted planes at 85 mm, where it would have moved the
  // scale 7 %).
  double min_improvement_over_translating_disk = 1.5;
  double max_relative_uncertainty = 0.05;
  // The blur search (max_radius_px must match the crops' border).
  BlurEstimationOptions blur;
  int num_threads = -1;
  uint64_t seed = 42;
  bool Check(std::string* failure = nullptr) const;
};

struct SplitProfileFit {
  bool determined = false;
  std::string reason;  // why not determined, or a summary when it is
  // Radii unknown (self-calibration); else known-radius calibration.
  bool self_calibrated = false;
  // Self-calibration also weighs the translating disk itself (the paper's
  // model, not a member of the family: its views sum to a disk weighted by
  // chord length): true unless the best split profile explains the data
  // significantly better; then it is the fit (`params` unused).
  bool translating_disk = false;
  double translating_disk_criterion = 0;
  SplitProfileParams params;
  // Centroid offset per radius of the fitted profile and of the translating
  // disk (at 8 px): their ratio is roughly the factor by which radii (and
  // the scale) change against a translating-disk estimate.
  double centroid_offset = 0;
  double centroid_offset_ci_low = 0, centroid_offset_ci_high = 0;
  // Self-calibration: the centroid offsets the data allow (the bootstrap
  // interval, the translating disk's when it fits as well, and every
  // evaluated profile within consistency_tolerance of the minimum; the
  // family's limit where the minimum lies at the edge of the range). The
  // scale is uncertain by the same factors.
  double consistent_low = 0, consistent_high = 0;
  bool at_edge = false;
  double translating_disk_centroid_offset = 0;
  int num_patches = 0;
  // Mean relative residual of the patches at the fitted profile, and median
  // |r_recovered / r_known - 1| (calibration only, else NaN).
  double mean_relative_residual = 0;
  double median_radius_error = std::numeric_limits<double>::quiet_NaN();
  // The criterion over the evaluated centroid offsets (sorted).
  std::vector<double> centroid_offsets, criterion;
  double seconds = 0;
};

SplitProfileFit FitSplitProfile(const std::vector<ProfilePatch>& patches,
                                const SplitProfileFitOptions& options);

// The blur search of every patch (crops of one size) under one profile, in
// parallel (num_threads -1 = all). An estimate that failed, lies at the
// bound or is not finite comes back with valid = false. `prepared`: what
// the search needs of the patches whatever the profile (PreparedBlurPatch),
// filled by the first call when empty and reused by the next ones on the
// same patches and options: a search along the family's path makes one call
// per profile.
std::vector<PatchBlurEstimate> EstimateProfilePatches(
    const DPPsfModel& psf,
    const BlurEstimationOptions& blur,
    const std::vector<const ProfilePatch*>& patches,
    int num_threads,
    std::vector<PreparedBlurPatch>* prepared);

// Calibration from captures of known blur, for the whole frame and for
// `num_bands` equal-width column bands: real DP profiles change across the
// frame. The bands are used (banded = true) when every band's fit is
// determined and some band's centroid offset differs from the whole
// frame's by more than `min_band_difference` (relative) with the frame's
// outside that band's 95 % interval, or the whole frame's is not
// determined; otherwise the whole-frame profile is the calibration. Works
// for known radii and for self-calibration alike.
struct SplitProfileCalibration {
  SplitProfileFit frame;
  std::vector<SplitProfileFit> bands;
  bool banded = false;
  std::string summary;
  // Patch searches read from a ProfileSearchCache and run (per patch and
  // profile).
  int searches_reused = 0, searches_run = 0;
};
// The blur searches of one CalibrateSplitProfile kept for the next (the
// view budget's checkpoints fit the profile again to the stored crops of
// the views they share): per crop, known by its pixels, and per profile,
// the estimate's radius and residual. A search depends on nothing but the
// crop's pixels (compared byte for byte), the profile and the blur options
// (every field), so a later calibration with the same options reads it
// where it would search and fits the same, to the bit. Holds what the last
// calibration used; one calibration at a time.
class ProfileSearchCache {
 public:
  ProfileSearchCache();
  ~ProfileSearchCache();
  ProfileSearchCache(const ProfileSearchCache&) = delete;
  ProfileSearchCache& operator=(const ProfileSearchCache&) = delete;

  // Crops held (a calibration's counts are in its result).
  int NumCrops() const;

  struct Impl;  // psf_calibration.cc
  Impl& impl() { return *impl_; }

 private:
  std::unique_ptr<Impl> impl_;
};

// bands_when_frame_fits = false fits the bands only when the whole frame's
// profile is not determined (self-calibration: saves their cost when one
// profile explains the data). `cache` (optional) carries the patch
// searches from one calibration to the next.
SplitProfileCalibration CalibrateSplitProfile(
    const std::vector<ProfilePatch>& patches,
    int num_bands,
    const SplitProfileFitOptions& options,
    double min_band_difference = 0.02,
    bool bands_when_frame_fits = true,
    ProfileSearchCache* cache = nullptr);

// Calibration captures: the textured patches of a DP pair of a planar,
// fronto-parallel target (one blur radius over the frame). Grey CV_32FC1
// views; patches of patch_size + 2 border px on a `stride` grid whose
// texture clears min_texture_snr times what noise alone gives; each carries
// known_radius_px.
std::vector<ProfilePatch> ExtractProfilePatches(const cv::Mat& gray_left,
                                                const cv::Mat& gray_right,
                                                int patch_size,
                                                int stride,
                                                int border,
                                                double known_radius_px,
                                                double min_texture_snr);

}  // namespace dpsfm
