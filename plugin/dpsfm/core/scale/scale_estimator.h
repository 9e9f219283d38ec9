// The whole DP-SfM scale pipeline behind one class: per-view patch blur
// estimation (AddView), then the linear initial estimate with view selection
// and the intensity-based search (Estimate). Images, depths and lens data in,
// numbers out; no files, no COLMAP types.
//
// Scale convention: metric metres = s * model units.
#pragma once

#include <cstdint>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/blur/patch_grid.h"
#include "dpsfm/core/calibration/psf_calibration.h"
#include "dpsfm/core/optics/dp_psf.h"
#include "dpsfm/core/optics/encoding.h"
#include "dpsfm/core/optics/lens_model.h"
#include "dpsfm/core/scale/intensity_search.h"
#include "dpsfm/core/scale/linear_estimator.h"
#include "dpsfm/core/scale/refusal.h"
#include "dpsfm/core/scale/scale_cues.h"

namespace dpsfm {

class BlurSearchEstimators;  // view_patches.h

// What the DP frames were before they reached the core in linear light:
// reported with the view, and what an 8-bit or lossy file costs is said.
struct DPFrameInfo {
  DPEncoding encoding = DPEncoding::kLinear;
  std::string encoding_reason;  // which rule decided it
  int bits = 16;
  bool lossy = false;
};

struct DPView {
  std::string name;
  // Same size, CV_32FC1 or CV_32FC3, linear light in [0, 1]
  // (core/optics/encoding.h). Left/right follow the CLI contract (a nearer
  // point lies towards +x in the left view).
  cv::Mat left, right;
  // Empty: left and right are the frames as captured. Otherwise their size
  // as captured, and left/right already reduced to the working resolution
  // (DPScaleEstimator::ReduceFrame).
  cv::Size frame_size;
  DPFrameInfo frames;
  DPLensData lens;
  // Dense mode: CV_32FC1 z' covering the same field as the frame at any
  // resolution: frame pixel (x, y) <-> depth pixel (x * dw / W, y * dh / H);
  // <= 0 or non-finite = invalid.
  cv::Mat depth;
  // Sparse mode (used when `depth` is empty): the same patch grid as the
  // dense mode; a patch takes the median depth of the points inside it and
  // needs PatchSelectionOptions::min_depth_points_per_patch of them, so patches
  // sit where the points are and spread as they do.
  std::vector<DepthPoint> depth_points;
};

// Patch geometry, in pixels of the working frame (the DP frame resized by
// resize_factor). 0 = automatic from DefaultPatchGeometry. An explicit
// max_radius_px sets how far the blur search reaches (and turns its growth
// off), not the patches: they are the automatic bound's.
struct PatchGeometryOptions {
  int patch_size = 0;
  int stride = 0;
  double max_radius_px = 0;
  double resize_factor = 0;
  // The automatic bound is at least this (e.g. the blur a calibrated
  // profile was measured at: the frame-size rule assumes full-resolution
  // pixels and reads ~3.5 px for 512 px frames of a downsampled full-frame
  // sensor whose scenes blur up to ~8 px), with the patch and stride that
  // go with it, which an explicit max_radius_px keeps. 0 = the frame-size
  // rule alone.
  double min_auto_radius_px = 0;
  // With max_radius_px automatic, the bound is the view's own: when at
  // least this share of a view's searched patches lie beyond the bound
  // (BlurEvidence::kBeyondBound: dropping them keeps only the patches
  // nearer the focus; on the R6 II's box/002, 114 of 289 at 4.93 px moved
  // the answer by 7 %), the view is searched again with twice the bound
  // (GrownSearchBound), up to max_search_bound_growths times. A result
  // that still has this share beyond the bound says so (DPScaleResult::
  // search_bound).
  double search_bound_share = 0.05;
  int max_search_bound_growths = 1;
  // The largest blur (px) a measured-kernel profile's calibration covered
  // (0: not known, or a model profile, which extends by its formula).
  // Beyond it the kernels are magnified copies of the measured ones, and
  // the intervals carry an extrapolation term (DPScaleResult::
  // search_bound.extrapolation_uncertainty).
  double profile_covered_radius_px = 0;

  bool Check(std::string* failure = nullptr) const;
};

// Which patches a view keeps: their depth and texture, the blur search's
// share, the top T_c selection, and the crops kept for the later stages.
struct PatchSelectionOptions {
  // T_c: fraction of a view's valid patches kept, by confidence.
  double top_patch_fraction = 0.1;
  // Keep at least this many per view when available (a view needs
  // LinearEstimatorOptions::min_samples_per_view for its own solve).
  int min_patches_per_view = 8;
  // The T_c patches are shared among this many equal-width bins of inverse
  // depth (see SelectTopFractionStratified); 1 = the paper's plain top T_c.
  int depth_strata = 4;
  // The blur search runs on this many times T_c of the patches that pass
  // the depth and texture checks, the best by the part of the confidence
  // known before the search (texture / depth variance; fit quality, the
  // rest, is <= 1), spread over depth like the final selection; the top
  // T_c share of all is then kept from the searched ones. 0 = search every
  // patch (the paper's order; ~1 / (factor T_c) times slower).
  double blur_search_factor = 3;
  // Memory bound: at most this many patches per view keep their image crops
  // for the intensity stage (the highest-confidence ones), and at most
  // `max_stored_megabytes_per_view` of crops. The intensity stage should see
  // the patches the linear stage used: with only the top 64 it read a
  // different subset and disagreed with the linear stage by up to 0.8 % on
  // the example scenes (worse than linear on average); with all selected
  // patches it is better than linear on average. 16 MB hold ~680 crops of
  // 45 px (1200x800 frames) or ~57 of 153 px (DSLR frames at the
  // reference's resize 0.5), counted with the blur stage's border
  // (self-calibration's wider crops take up to ~1.6x that; overlapping
  // crops share their frames' region instead when it is smaller,
  // StoreCrops).
  int max_stored_patches_per_view = 256;
  double max_stored_megabytes_per_view = 16;
  // A patch needs depth on this fraction of its pixels (dense mode)...
  double min_depth_coverage = 0.5;
  // ...or this many depth points inside it (sparse mode).
  int min_depth_points_per_patch = 3;
  // Patches whose horizontal texture is below this multiple of what sensor
  // noise alone produces are dropped: their blur "estimate" fits the noise.
  // (Texture is the blur estimator's mean |horizontal Sobel| of left + right;
  // pure noise of std sigma per view gives about 3.9 sigma, i.e. a ratio of
  // 1.00 +- 0.05 on patches of ~50 px; 1.3 sits well above that.)
  double min_texture_snr = 1.3;
  // Patches whose depth varies more than this inside (robust relative
  // spread, (p90 - p10) / median) straddle a depth edge: the blur model
  // assumes one depth per patch, so they are dropped.
  double max_relative_depth_spread = 0.1;
  // Patches the blur model does not explain are dropped: relative residual
  // (PatchBlurEstimate::relative_residual) above the larger of this and
  // `relative_residual_factor` x the view's median. A patch whose true blur
  // lies beyond the search bound fits no kernel pair and leaves >= ~0.3 % of
  // its structure unexplained (while a spurious small radius may still be
  // the loss's minimum); well-fitting patches leave < 0.1 %. The relative
  // part keeps a PSF profile that fits every patch a little worse (a real
  // sensor) from losing all patches.
  double max_relative_residual = 0.002;
  double relative_residual_factor = 10;

  bool Check(std::string* failure = nullptr) const;
};

// The intensity stage (candidates, T_s, refine pass, loss, bootstrap).
struct IntensityStageOptions {
  bool enabled = true;
  // The search. Its seed and num_threads are replaced by DPScaleOptions',
  // and its max_radius_px by the patch geometry's (the crops' border
  // supports exactly that).
  IntensitySearchOptions search;
  // The intensity scale replaces the linear one only if its bootstrap
  // interval is narrower than this fraction of the scale, its minimum is
  // inside the searched range, and at least this share of bootstrap
  // resamples agree with it; otherwise the linear scale is kept and the
  // result says why (the stage never makes things worse silently).
  double max_ci_relative_width = 0.3;
  double min_bootstrap_support = 0.5;

  bool Check(std::string* failure = nullptr) const;
};

// When a scale is reported, and the terms of its interval.
struct ScaleIntervalOptions {
  // Refusal: a scale is reported only if its 95 % interval (the linear
  // stage's bootstrap, the systematic term and the DP profile's own
  // uncertainty) is narrower than this fraction of it and the joint solve
  // has at least `min_total_patches` patches; otherwise success = false
  // with the reason (a confident wrong scale is worse than none). Noisy or
  // textureless captures and pan-focus ones fail here. 0.3 (+-15 %) lets
  // single real views with a calibrated profile answer (the Canon R6 II
  // scenes: 22-24 % wide, holding the truth); the paper's real-data error
  // is 15 %.
  double max_scale_ci_relative_width = 0.3;
  int min_total_patches = 10;
  // Relative systematic uncertainty of a blur estimate that no resampling
  // sees (PSF profile, renderer/sensor details; the translating-disk
  // estimator is calibrated to ~0.5 % on ideal data): added in quadrature
  // to each half of the reported intervals, so that they cover the truth
  // when the patches agree with each other better than with the world.
  double scale_systematic_uncertainty = 0.01;
  // Relative (95 %) uncertainty of a given profile's strength, e.g. a
  // calibration's interval: the scale ~ the strength, so the intervals are
  // widened by the factors 1 -+ this.
  double profile_relative_uncertainty = 0;
  // The thin lens has one plane where a real lens has two principal planes
  // and an entrance pupil (the origin of SfM depth), within about a focal
  // length of each other; the intervals carry a relative depth error of
  // this times f / z at the patches' median distance (in quadrature with
  // the term above). 0 disables it (a thin-lens camera, e.g. renders).
  double lens_geometry_uncertainty = 1;
  // Recorded focus distances (DPLensData::recorded_focus_mm) are taken as
  // accurate to this fraction (95 %), in quadrature with the window the
  // record itself gives (DPLensData::recorded_focus_bracket): a camera's
  // focus encoder reports steps, a lens's distance scale and a tape from
  // the lens front are centimetres off the focal-plane mark
  // (docs/psf-profiles.md, "The recorded focus").
  double recorded_focus_tolerance = 0.15;
  // Use the recorded focus as a second cue to the scale
  // (core/scale/scale_cues.h): the answer combines it with the DP data (their
  // inverse-variance mean when they agree, an interval covering both when they
  // do not; see CombineScaleCues), and stands in for the DP data when the
  // profile leaves the scale open. Off: the recorded focus is evidence only
  // (the report's focus_check), and such runs refuse.
  bool pin_to_recorded_focus = true;

  bool Check(std::string* failure = nullptr) const;
};

// DP PSF self-calibration: before the linear stage, fit the split profile
// to the stored patches of all views, for the whole frame and for `bands`
// column bands (CalibrateSplitProfile).
struct SelfCalibrationOptions {
  // - kFit (the `auto` profile, issue 7): when the data determine a profile
  //   other than the translating disk, the stored patches' blur is searched
  //   again with it (each band's where the profile changes across the
  //   frame) and both stages use those patches and profiles; otherwise the
  //   given PSF is kept and the result says why.
  // - kCheck (the translating disk, chosen explicitly by the user): the fit
  //   only checks the given disk and never replaces it. When the data
  //   determine another profile the run refuses (the paper's disk is not
  //   this sensor's: the R6 II's real scenes read 2.2-2.8x off under it
  //   with narrow intervals, docs/psf-profiles.md); when they cannot
  //   determine one, the scale carries the range of profiles they allow, as
  //   under kFit. A model chosen without evidence from this camera is
  //   checked, not trusted.
  // - kOff: the profile is given (calibrated) and taken as it is.
  enum class Mode { kOff, kFit, kCheck };
  Mode mode = Mode::kOff;
  SplitProfileFitOptions fit;
  // At most this many patches feed the fit (evenly over the views).
  int max_patches = 400;
  // The fit uses patches on surfaces nearly parallel to the sensor (depth
  // spread inside at most this), or the flattest 2 x fit.min_patches if
  // fewer: a blur gradient inside a patch is fitted better by a softer
  // split and biased the fit (a translating-disk scene of slanted planes at
  // 85 mm read 7 % small with all patches).
  double max_depth_spread = 0.02;
  // Self-calibration searches blur up to this multiple of the blur stage's
  // bound, and the stored crops carry the border for it: the translating
  // disk reads a softer true split's blur up to ~1.5x small, so the true
  // blur of the patches it selected can lie beyond its own bound (with the
  // bound as it was, the true profile lost those patches and the fit was
  // pulled back towards the translating disk: generated soft-split scenes
  // fitted p ~1.1 instead of 2.2).
  double radius_factor = 2;
  int bands = 3;
  // Relative (95 %) uncertainty of a self-calibrated profile's strength
  // beyond its fit, applied when a fitted profile replaces the translating
  // disk: the cross-view identity G_l * H_r = G_r * H_l holds for any pair
  // sharing a common factor with the true one, so a family member can fit
  // a sensor outside the family perfectly at the wrong strength (an
  // apodized soft split: residual 0, centroid offset 0.164 R for 0.132 R,
  // scale 18 % off; psf_profile_bench). 0 trusts the family.
  double shape_uncertainty = 0.2;

  bool Check(std::string* failure = nullptr) const;
};

// DPScaleEstimator's options, by the stage or question they concern; Check()
// checks each group with its own Check().
struct DPScaleOptions {
  PatchGeometryOptions geometry;
  // Per-patch blur search (max_radius_px is taken from the geometry).
  BlurEstimationOptions blur;
  PatchSelectionOptions patches;
  // Linear stage (T_p, N_v, IRLS, bootstrap). Its seed and num_threads are
  // replaced by the fields below.
  LinearEstimatorOptions linear;
  IntensityStageOptions intensity;
  ScaleIntervalOptions interval;
  SelfCalibrationOptions self_calibration;

  // OpenMP threads for blur estimation, the linear stage's bootstrap and
  // the intensity search; -1 = all.
  int num_threads = -1;
  uint64_t seed = 42;

  bool Check(std::string* failure = nullptr) const;
};

// What AddView did with one view.
struct DPViewSummary {
  std::string name;
  DPFrameInfo frames;
  int index = -1;
  cv::Size frame_size;
  cv::Size working_size;
  double resize_factor = 1;
  int patch_size = 0;
  int stride = 0;
  double max_radius_px = 0;
  int patches_tried = 0;  // grid positions
  int patches_with_depth = 0;
  int patches_searched = 0;  // blur search run (see blur_search_factor)
  // The search bound the geometry gave, how often it grew
  // (PatchGeometryOptions::search_bound_share), and the searched patches at the
  // final bound (max_radius_px) by what their loss curves say
  // (BlurEvidence): beyond the bound, and undetermined (within the patch's
  // noise; left out).
  double initial_max_radius_px = 0;
  int search_bound_growths = 0;
  int patches_beyond_bound = 0;
  int patches_undetermined = 0;
  int patches_valid = 0;  // usable blur estimates
  int patches_kept = 0;   // top-T_c
  double seconds = 0;
  // Patch rejection counts by reason (e.g. {"without depth", 12}).
  std::vector<std::pair<std::string, int>> rejections;
};

struct PatchSample {
  int view = -1;
  int psf_band = 0;            // cell of the DP PSF's layout (constructor)
  double x = 0, y = 0;         // centre, DP-frame pixels
  double depth = 0;            // z'
  double depth_spread = 0;     // (p90 - p10) / median of z' inside
  double radius_px = 0;        // signed estimate, working-frame pixels
  double radius_frame_px = 0;  // the same in DP-frame pixels
  // Standard error of radius_px from the patch's loss curve (working-frame
  // px; PatchBlurEstimate::radius_se_px).
  double radius_se_px = 0;
  double confidence = 0;
  double fit_quality = 0;
  double texture = 0;
  double texture_snr = 0;  // texture / (texture of noise alone)
  bool selected = false;   // among the view's top T_c
  bool used = false;       // selected and its view used
  // Radius predicted by the final (s, g_i') in working-frame pixels (NaN if
  // the view has no focus distance).
  double predicted_radius_px = 0;
};

struct DPViewResult {
  std::string name;
  DPFrameInfo frames;
  bool used = false;
  std::string reason;
  double focus_distance_model = 0;  // g' (model units); NaN if unknown
  double focus_distance_m = 0;      // s * g'
  double single_view_scale = 0;     // NaN if the view could not be solved
  // The recorded focus (m, from the focal-plane mark; NaN if none) and the
  // scale it implies with the fitted focal plane g' (profile-free: where
  // the disparity changes sign does not depend on the DP profile).
  double recorded_focus_m = std::numeric_limits<double>::quiet_NaN();
  double focus_scale = std::numeric_limits<double>::quiet_NaN();
  double predicted_blur_range_px = 0;
  double median_abs_residual_px = 0;
  int patches_tried = 0;
  int patches_searched = 0;
  int patches_valid = 0;
  int patches_selected = 0;
  DPLensData lens;
};

// The blur-search bound as the views ended with it
// (PatchGeometryOptions::search_bound_share), and how far a measured profile
// was extended beyond the blur its calibration covered.
struct SearchBoundAccount {
  double initial_max_radius_px = 0;  // the largest bound the geometry gave
  double max_radius_px = 0;          // the largest bound searched
  int views_grown = 0;               // views searched again with a larger one
  int patches_searched = 0;          // at the final bounds, all views
  int patches_beyond_bound = 0;      // BlurEvidence::kBeyondBound
  int patches_undetermined = 0;      // BlurEvidence::kUndetermined
  // At least search_bound_share of the searched patches still lie beyond
  // the bound: the answer rests on the patches
  // nearer the focus, and a larger bound may move it.
  bool limits = false;
  // The bound that would search farther (LargerSearchBound, whole px).
  double larger_radius_px = 0;
  // PatchGeometryOptions::profile_covered_radius_px, the selected patches of
  // the used views beyond it, of all of them, and the relative (95 %) term the
  // extrapolation adds to the profile's uncertainty (in quadrature): the
  // profile's uncertainty times the share beyond times the median
  // ln(|r| / covered) of those beyond (0 when none are).
  double profile_covered_radius_px = 0;
  int samples_beyond_coverage = 0;
  int samples = 0;
  double extrapolation_uncertainty = 0;
};

// The intensity stage: whether its scale was adopted, and why (not).
struct IntensityStageResult {
  bool used = false;
  std::string status;
  double scale = 0;  // the search's minimiser (even if not used)
  double ci_low = 0, ci_high = 0;
  // Share of bootstrap resamples whose minimum lies within one first-pass
  // step of `scale`.
  double bootstrap_support = 0;
  std::string loss;
  // Patch loss evaluations of the search that threw and counted as nothing.
  int failed_evaluations = 0;
  // Its node statistics taken from an earlier Estimate's (the view
  // budget's checkpoints) and computed.
  int nodes_reused = 0, nodes_computed = 0;
  // Intensity loss curve for the report plot.
  std::vector<double> candidate_scales, candidate_losses;
};

// The DP PSF the stages used, what self-calibration did, and how far the
// profiles the data allow move the scale.
struct DPPsfResult {
  // The DP PSF the stages used (DPPsfModel::Name()), and what
  // self-calibration did ("" when it was off).
  std::string model;
  std::string status;
  bool self_calibrated = false;  // a fitted profile replaced the given one
  // SelfCalibrationOptions::Mode::kCheck: the data determined another
  // profile than the given translating disk (the run refuses: refusal.disk;
  // status is then "", the refusal's wording stands for it).
  bool rejected = false;
  // Whether self-calibration fitted a profile (`fit` holds its fit).
  bool fit_ran = false;
  // The whole frame's fit (and, for a profile changing across the frame,
  // the bands' fits, left to right, when they were used).
  SplitProfileFit fit;
  std::vector<SplitProfileFit> band_fits;
  // Its patch searches read from an earlier Estimate's (the view budget's
  // checkpoints) and run.
  int fit_searches_reused = 0, fit_searches_run = 0;
  // The factors by which the profiles the data allow move the scale
  // against the one used (self-calibration: the fits' consistent centroid
  // offsets over the one used; 1 when the profile was given). The reported
  // intervals include them; 0 / inf = not bounded.
  double scale_factor_low = 1, scale_factor_high = 1;
};

// The two cues (core/scale/scale_cues.h), how the answer was formed from
// them, and the recorded focus distances as evidence.
struct ScaleCuesResult {
  // `dp` is the DP data's own estimate and interval (valid = false when
  // they give none), `focus` the recorded focus's.
  ScaleCue dp, focus;
  CueAgreement agreement = CueAgreement::kOneCue;
  bool combined = false;  // the answer came through CombineScaleCues
  std::string source;     // "DP data", "recorded focus", or both
  // How the cues formed the answer (CombinedScale::how); "" when the DP
  // data answered alone (dp_data_alone: the COLMAP layer words it, naming
  // the option that keeps the recorded focus out).
  std::string combination;
  bool dp_data_alone = false;
  // The scale (and interval) came from the recorded focus distances, the
  // profile having left it open (ScaleIntervalOptions::
  // pin_to_recorded_focus); the profile strength that reconciles the DP
  // data with it, relative to the one used.
  bool scale_from_recorded_focus = false;
  double pinned_profile_strength = 0;
  // Focus distances as evidence: the median scale the recorded focus
  // distances imply (NaN without any), the DP data's scale over it,
  // whether they agree within the interval and ScaleIntervalOptions::
  // recorded_focus_tolerance, and a sentence for people.
  double focus_scale = 0;
  double focus_scale_ratio = 0;
  bool focus_agrees = true;
  std::string focus_check;
};

// Wall time of each stage (s).
struct StageSeconds {
  double blur = 0, psf_fit = 0, linear = 0, intensity = 0;
};

// What Estimate found: the answer (or the refusal) at the top, and each
// stage's account in its own group.
struct DPScaleResult {
  bool success = false;
  // Why not (refusal.h; colmap/report/refusal_text words it).
  DPScaleRefusal refusal;
  double scale = 0;          // final s (metres per model unit)
  double scale_initial = 0;  // linear-stage s*
  double scale_ci_low = 0, scale_ci_high = 0;  // of `scale`
  double scale_initial_ci_low = 0, scale_initial_ci_high = 0;
  int num_patches = 0;  // patches in the final solve
  int num_views_used = 0;
  double linear_median_abs_residual_px = 0;
  // The relative systematic term of the lens geometry (see
  // ScaleIntervalOptions::lens_geometry_uncertainty).
  double lens_geometry_uncertainty = 0;
  std::vector<DPViewResult> views;
  std::vector<PatchSample> patches;
  IntensityStageResult intensity;
  DPPsfResult psf;
  ScaleCuesResult cues;
  SearchBoundAccount search_bound;
  StageSeconds seconds;
};

// What one run's estimates keep for the next: the view budget's checkpoints
// estimate again over the views they share, and read here the searches an
// earlier estimate made instead of repeating them (the same answers, to the
// bit: each cache's key holds everything its values depend on;
// intensity_search.h, psf_calibration.h). Owned by the run; one estimate at
// a time.
struct EstimateCaches {
  IntensityStatsCache intensity;  // the intensity stage's crop statistics
  ProfileSearchCache profile;     // the profile fit's patch searches
};

class DPScaleEstimator {
 public:
  DPScaleEstimator(const DPScaleOptions& options,
                   std::shared_ptr<const DPPsfModel> psf);
  // A profile that changes across the frame: field.cells[k] serves the
  // patches whose centre lies in cell k of field.layout, in every stage.
  // Self-calibration needs a single cell.
  DPScaleEstimator(const DPScaleOptions& options, DPPsfField field);
  ~DPScaleEstimator();

  // Estimates patch blurs in one view and keeps only what later stages need
  // (samples + crops of the top-T_c patches), so memory stays bounded for
  // 30+ large views. Throws std::invalid_argument (naming the view) for
  // malformed input: empty or mismatched images, bad lens data, neither depth
  // map nor points. Data that merely carry no information (no texture, no
  // depth) are recorded, not thrown.
  DPViewSummary AddView(const DPView& view);

  // A view's frame (left or right, as captured) reduced to the working
  // resolution AddView searches it at (ViewPatchGeometry of its size), as
  // AddView would reduce it: a view whose frames a reader reduced (with
  // DPView::frame_size their size as captured) gives AddView's result for
  // the view as captured. A reader calls it on its own thread (it reads only
  // the options) so that views waiting hold their working frames alone (a
  // quarter of a 3000 x 2000 view's).
  cv::Mat ReduceFrame(const cv::Mat& frame) const;
  // The same for `rows` of a frame of `frame_size` (the reduction is the
  // whole frame's): all of them, or a strip of a multiple of
  // ReduceFrameStripRows(frame_size) rows, whose share of the reduced frame
  // it gives, to the bit, so that a reader may reduce a frame a strip at a
  // time. ReduceFrameStripRows is 0 where only whole frames may be reduced
  // (WorkingFrameStripRows).
  cv::Mat ReduceFrame(const cv::Mat& rows, const cv::Size& frame_size) const;
  int ReduceFrameStripRows(const cv::Size& frame_size) const;

  int NumViews() const;

  // Linear stage (per-view solves, view selection, joint solve) then the
  // intensity stage. Never throws for bad data: success = false with a reason
  // a user understands. `caches` (optional, the run's): the searches an
  // earlier estimate over some of the same views made, read where this one
  // would repeat them, and this one's kept for the next.
  DPScaleResult Estimate(EstimateCaches* caches = nullptr) const;

 private:
  struct ViewData;
  struct IntervalTerms;
  // The linear interval before the profile's term (scale_estimator_data.h).
  struct StatisticalInterval;
  // The steps of Estimate, in order (scale_estimator.cc).
  // Self-calibration, when the options ask for it: the fitted profile and
  // the samples re-estimated with it replace *field and *samples.
  void SelfCalibrate(EstimateCaches* caches,
                     std::vector<std::vector<PatchSample>>* samples,
                     DPPsfField* field,
                     DPScaleResult* result) const;
  // The linear stage on the selected samples; false (the refusal set) if
  // it threw.
  bool LinearStage(const std::vector<std::vector<PatchSample>>& samples,
                   LinearEstimate* linear,
                   DPScaleResult* result) const;
  // Each view's result and every patch, as the linear stage left them.
  void AddViewResults(const LinearEstimate& linear,
                      const std::vector<std::vector<PatchSample>>& samples,
                      DPScaleResult* result) const;
  // Where the patches went, summed over views (refusal.h).
  PatchAccount AccountForPatches() const;
  // The lens geometry's relative systematic term (see
  // ScaleIntervalOptions::lens_geometry_uncertainty): f / z at the selected
  // patches' median distance, times the option.
  double LensGeometryTerm(
      const LinearEstimate& linear,
      const std::vector<std::vector<PatchSample>>& samples) const;
  // The views' final search bounds (DPScaleResult::search_bound).
  SearchBoundAccount AccountForSearchBound() const;
  // The selected patches beyond the blur a measured profile covered, and
  // the term that carries the extrapolation (before SetProfileScaleFactors,
  // which adds it to the profile's uncertainty).
  void AccountForExtrapolation(
      const LinearEstimate& linear,
      const std::vector<std::vector<PatchSample>>& samples,
      SearchBoundAccount* bound) const;
  // result->psf.scale_factor_low/high: what the profile leaves open.
  void SetProfileScaleFactors(const DPPsfField& field,
                              DPScaleResult* result) const;
  // The refusal of a linear stage that found no scale, with how far the
  // profile's reading of the blur could be off.
  void RefuseLinearFailure(const LinearEstimate& linear,
                           const DPPsfField& field,
                           const PatchAccount& account,
                           DPScaleResult* result) const;
  // Widens linear's interval by the systematic terms, the lens geometry's
  // and the profile's (returned; *statistical: the interval before the
  // profile's term).
  IntervalTerms WidenLinearInterval(
      const std::vector<std::vector<PatchSample>>& samples,
      const DPPsfField& field,
      LinearEstimate* linear,
      StatisticalInterval* statistical,
      DPScaleResult* result) const;
  // The cues, then the linear stage's answer (or the cues' combined one
  // where the DP data alone leave the scale open) in *result; false with
  // the refusal set when neither answers.
  bool AdoptLinearStage(const LinearEstimate& linear,
                        const StatisticalInterval& statistical,
                        const PatchAccount& account,
                        DPScaleResult* result) const;
  // Why the DP data alone give no scale (cause kNone when they give one):
  // too few patches, no interval, or an interval too wide (and whether the
  // profile or the data leave it open).
  OpenScale LinearRefusal(const LinearEstimate& linear,
                          double statistical_width,
                          double statistical_ci_low,
                          double statistical_ci_high,
                          const DPScaleResult& result) const;
  // Whether the recorded-focus cue joins the answer:
  // interval.pin_to_recorded_focus and a valid cue in `result`.
  bool RecordedFocusJoins(const DPScaleResult& result) const;
  // After the DP data answered on their own: their cue, and the recorded
  // focus's joining it (RecordedFocusJoins); false (the refusal set) when
  // the two disagree beyond what may be printed.
  bool JoinRecordedFocus(const LinearEstimate& linear,
                         DPScaleResult* result) const;
  // Focus distances and predicted blur radii under the final scale.
  void PredictUnderFinalScale(DPScaleResult* result) const;
  // The intensity stage (intensity_stage.cc): refines the linear scale on the
  // selected views' stored crops; fills result->intensity and,
  // when its estimate is used, the scale and its interval (widened by
  // `terms`).
  void IntensityStage(const LinearEstimate& linear,
                      const std::vector<std::vector<PatchSample>>& samples,
                      const DPPsfField& field,
                      const IntervalTerms& terms,
                      IntensityStatsCache* cache,
                      DPScaleResult* result) const;
  // Self-calibration (profile_self_calibration.cc): fits the split profile
  // to the stored patches and, if it replaces the given PSF, re-estimates
  // them (samples[i] of view i; only the stored ones stay selected) and
  // sets *field.
  void CalibrateProfile(std::vector<std::vector<PatchSample>>* samples,
                        DPPsfField* field,
                        ProfileSearchCache* cache,
                        DPScaleResult* result) const;
  // SelfCalibration::kCheck: what the fit says of the given translating
  // disk (agrees, cannot tell, or rejects it: DPPsfResult::rejected).
  void CheckTranslatingDisk(const SplitProfileCalibration& calibration,
                            DPScaleResult* result) const;
  // A stored crop: its view and its index among the view's stored crops.
  struct StoredRef {
    int view, stored;
  };
  // Stored crops by geometry (crop size, radius bound).
  using StoredGroups = std::map<std::pair<int, double>, std::vector<StoredRef>>;
  StoredGroups GroupStoredCrops() const;
  // The group's flat crops (self_calibration.max_depth_spread; the flattest
  // 2 min_patches when too few are flat), evenly over the views, at most
  // self_calibration.max_patches.
  std::vector<ProfilePatch> ProfileFitPatches(
      const std::vector<StoredRef>& group, int min_patches) const;
  // Searches every stored crop again with its cell's fitted profile; the
  // count re-estimated (those that fit become selected), and in *failures
  // those whose search threw.
  int ReestimateStoredPatches(
      const StoredGroups& groups,
      const std::vector<std::shared_ptr<const DPPsfModel>>& fitted,
      std::vector<std::vector<PatchSample>>* samples,
      int* failures) const;
  // Fills the focus_* fields of result->cues (recorded focus as evidence).
  void CheckAgainstRecordedFocus(DPScaleResult* result) const;
  // The DP data's cue from the linear stage (invalid with too few patches
  // or no finite positive interval).
  ScaleCue DPCue(const LinearEstimate& linear) const;
  // The recorded focus's cue: the used views' recorded focus distances over
  // their fitted focal planes g' (median), with the bootstrap's interval
  // widened by the record's tolerance and bracket (ScaleIntervalOptions::
  // recorded_focus_tolerance); invalid without a recorded focus.
  ScaleCue RecordedFocusCue(const LinearEstimate& linear,
                            double lens_geometry) const;
  // No selected view recorded a focus distance (which would give the scale
  // without the DP profile).
  bool RecordedFocusMissing(const LinearEstimate& linear) const;
  // Forms the answer from result->cues.dp and result->cues.focus
  // (CombineScaleCues) and returns true, or says why not in *refusal (too
  // wide, or the cues disagree).
  bool AdoptCombinedCues(const LinearEstimate& linear,
                         DPScaleResult* result,
                         CueRefusal* refusal) const;
  // See DPPsfResult::scale_factor_low.
  void ProfileScaleFactors(const DPPsfField& field,
                           const DPScaleResult& result,
                           double* low,
                           double* high) const;
  DPScaleOptions options_;
  DPPsfField field_;
  std::shared_ptr<const DPPsfModel> psf_;  // field_.cells[0]
  std::vector<std::unique_ptr<ViewData>> views_;
  // The blur search's tables, kept across views (view_patches.h).
  std::unique_ptr<BlurSearchEstimators> blur_estimators_;
};

}  // namespace dpsfm
