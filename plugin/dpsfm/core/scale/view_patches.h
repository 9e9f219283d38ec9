// One view's patches, from the grid to the stored crops: the steps
// DPScaleEstimator::AddView runs on each view, in order. The view is
// resampled to the working frame, the patch grid gets its depths
// (patch_grid.h), the patches are screened and the blur search runs on the
// chosen share (patch_selection.h, blur_estimation.h), the usable patches
// become samples, the top T_c of them are selected, and the best selected
// ones are kept as crops (crop_store.h) for the later stages.
#pragma once

#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/blur/crop_store.h"
#include "dpsfm/core/blur/patch_grid.h"
#include "dpsfm/core/blur/patch_selection.h"
#include "dpsfm/core/optics/dp_psf.h"
#include "dpsfm/core/scale/scale_estimator.h"

namespace dpsfm {

// Throws std::invalid_argument naming the view for malformed input (empty or
// mismatched images, bad lens data, neither depth map nor points).
void CheckViewInput(const DPView& view);

// The patch geometry of a frame: the reference defaults for its size, then
// the explicit options.
PatchGeometry ViewPatchGeometry(const cv::Size& frame_size,
                                const DPScaleOptions& options);

// The size of the view's frames as captured (DPView::frame_size).
cv::Size FrameSize(const DPView& view);

// A frame reduced by `resize_factor` (area-averaged: the anti-aliased
// resize the reference code uses); the frame itself when it is not reduced.
cv::Mat WorkingFrame(const cv::Mat& frame, double resize_factor);

// k > 0 when WorkingFrame of any strip of a multiple of k rows of a frame
// of this size gives those rows' share of WorkingFrame of the whole frame,
// to the bit: a reduction by an integer factor k to exactly frame / k
// (cv::INTER_AREA then averages whole k x k blocks, each on its own). 0
// otherwise, and without a reduction.
int WorkingFrameStripRows(const cv::Size& frame, double resize_factor);

// The view on the working frame (WorkingFrame, or the view's frames when
// a reader reduced them already: DPScaleEstimator::ReduceFrame) and its grey
// versions; sx, sy: working / frame pixels per axis (exact for the rounded
// size).
struct WorkingView {
  cv::Mat left, right;
  cv::Mat gray_left, gray_right;
  double sx = 1, sy = 1;
};
WorkingView MakeWorkingView(const DPView& view, double resize_factor);

// The border the blur search's kernel grid needs around a patch: the widest
// kernel of the field's profiles at the grid's bound (the search bound
// rounded up to a grid step).
int BlurSearchBorder(const DPPsfField& field,
                     const BlurEstimationOptions& blur,
                     double max_radius_px);

// Which cell of the field's layout serves a patch with this interior (on a
// working frame of `working_size`).
int PatchCell(const DPPsfField& field,
              const cv::Rect& interior,
              const cv::Size& working_size);

// Step 1: the patch grid and each patch's depth.
std::vector<PatchCandidate> PatchesWithDepth(const DPView& view,
                                             const WorkingView& working,
                                             const PatchGeometry& geometry,
                                             int border,
                                             const DPScaleOptions& options);

// Steps 2 and 3: screening, the blur-search share, and the blur search on
// the chosen patches (the expensive part, in parallel). A patch whose
// search throws is recorded as invalid with the exception's message.
// Searched in parts (ChooseViewSearch, then SearchChosenPatches on a share
// and on the rest), the estimates are those of one search of all: each
// patch's search is its own.
struct ViewBlurSearch {
  std::vector<PatchBlurEstimate> estimates;  // per candidate
  ScreenedPatches screened;
  std::vector<char> chosen;    // per candidate: to be searched
  std::vector<char> searched;  // per candidate: searched so far
  int num_searched = 0;
};

// The blur search's estimators, one per cell of a field, kept across views:
// their kernel tables cost tens of ms for the translating disk and up to a
// second for a measured kernel pair at a large bound, a measured field has
// one per cell, and the views of a project search crops of one size at one
// or two bounds (the first and the grown one). Known by the crop's side and
// every field of the search options (SameFields); the least recently used
// beyond the last kMaxGeometries is dropped (each holds a cell's tables: a
// few MB, tens for a large bound), and lives on while a caller holds it.
class BlurSearchEstimators {
 public:
  using Estimators = std::vector<std::unique_ptr<PatchBlurEstimator>>;
  static constexpr int kMaxGeometries = 2;

  // `field` must outlive this. Tables are built on num_threads threads
  // (-1: all).
  explicit BlurSearchEstimators(const DPPsfField& field, int num_threads = 1);

  // The field's estimators for square crops of side `crop` searched with
  // `blur`.
  std::shared_ptr<const Estimators> For(const BlurEstimationOptions& blur,
                                        int crop);

  // Tables built so far (for tests: views of one geometry build them once).
  int NumBuilt() const { return num_built_; }

 private:
  struct Geometry {
    int crop;
    BlurEstimationOptions blur;
    std::shared_ptr<const Estimators> estimators;
  };
  const DPPsfField& field_;
  const int num_threads_;
  std::vector<Geometry> geometries_;  // most recently used last
  int num_built_ = 0;
};

// Step 2: the screening and the blur-search share; nothing searched yet.
ViewBlurSearch ChooseViewSearch(const WorkingView& working,
                                const std::vector<PatchCandidate>& candidates,
                                int border,
                                bool any_depth,
                                const DPScaleOptions& options);

// Step 3: searches the chosen patches that `which` marks (all of them when
// null) and that were not searched yet. `cache`: the field's estimators
// (BlurSearchEstimators::For, asked only when a patch is to be searched),
// for crops of `patch_size` plus `border` on each side.
void SearchChosenPatches(const WorkingView& working,
                         const std::vector<PatchCandidate>& candidates,
                         const DPPsfField& field,
                         const BlurEstimationOptions& blur,
                         int border,
                         int patch_size,
                         const DPScaleOptions& options,
                         BlurSearchEstimators* cache,
                         const std::vector<char>* which,
                         ViewBlurSearch* search);

// Every kGrowthSampleStep-th chosen patch: the share whose search decides
// early that the bound grows (EarlyGrownSearchBound), or none when it
// would have fewer than kMinGrowthSample patches.
constexpr int kGrowthSampleStep = 4;
constexpr int kMinGrowthSample = 40;
std::vector<char> GrowthSample(const ViewBlurSearch& search);

// Searched patches whose blur lies beyond the search bound
// (BlurEvidence::kBeyondBound; their estimate is the bound, not the blur).
int PatchesAtSearchBound(const ViewBlurSearch& search);

// The next search bound after `bound_px`: 1.6 times it (at least 2 px
// more), rounded up to a half pixel (the blur grid's step). A bound 1.6
// times larger reaches the blur of points about that much farther from the
// focal plane in inverse depth.
double LargerSearchBound(double bound_px);

// Whether a view's search bound may still grow: an automatic bound
// (PatchGeometryOptions::max_radius_px 0) grown fewer than
// PatchGeometryOptions::max_search_bound_growths times.
bool SearchBoundMayGrow(int growths, const DPScaleOptions& options);

// Whether a view's search bound is to grow: only an automatic bound
// (PatchGeometryOptions::max_radius_px 0), when at least
// PatchGeometryOptions::search_bound_share of the searched patches sit at
// it, at most PatchGeometryOptions::max_search_bound_growths times.
bool SearchBoundReached(int num_searched,
                        int num_at_bound,
                        int growths,
                        const DPScaleOptions& options);

// The most a bound of `bound_px` grows to: twice it, up to a half pixel.
double SearchBoundCap(double bound_px);

// The bound to search the view again with, or 0 to keep its search: its
// cap (SearchBoundCap), else LargerSearchBound, the first whose crops (the
// same patch, the larger bound's kernel border) fit twice into the working
// frame's short side. Patches beyond the bound are evidence (BlurEvidence::
// kBeyondBound: the loss still falls into it by more than noise explains)
// that the blur runs past it, but not of how far, so the bound goes as far
// as the search affords rather than to an extrapolation of the usable
// patches, whose half-pixel steps moved answers.
double GrownSearchBound(const PatchGeometry& geometry,
                        const cv::Size& working_size,
                        const DPPsfField& field,
                        const BlurEstimationOptions& blur);

// The grown bound when the search of a share of the view's patches
// (GrowthSample) settles it, else 0 and the whole search decides (as
// SearchBoundReached and GrownSearchBound do): the share's patches beyond
// the bound exceed search_bound_share of them by two standard errors. A
// view whose blur runs well past its bound then searches a quarter of its
// patches at that bound instead of all before it is searched again; the
// answer is the same as the whole search's, which would have grown the
// bound too.
double EarlyGrownSearchBound(int num_searched,
                             int num_beyond_bound,
                             int growths,
                             const PatchGeometry& geometry,
                             const cv::Size& working_size,
                             const DPPsfField& field,
                             const BlurEstimationOptions& blur,
                             const DPScaleOptions& options);

// Step 4: usable patches become samples (of view `view_index`); the others
// are counted by reason in *rejections. *sample_candidate receives each
// sample's grid index.
std::vector<PatchSample> ViewSamples(
    const std::vector<PatchCandidate>& candidates,
    const ViewBlurSearch& search,
    const WorkingView& working,
    const DPPsfField& field,
    const PatchGeometry& geometry,
    int view_index,
    const DPScaleOptions& options,
    std::map<std::string, int>* rejections,
    std::vector<int>* sample_candidate);

// Step 5: the top T_c of the samples by confidence, stratified by depth (of
// all screened patches, taken from the searched ones; all of them when
// blur_search_factor is 0).
std::vector<int> SelectTopSamples(const std::vector<PatchSample>& samples,
                                  const ViewBlurSearch& search,
                                  const DPScaleOptions& options);

// Step 6: crops of the best selected patches (best first, within the
// memory budget) for the intensity stage and self-calibration. With
// self-calibration their border supports blur up to
// SelfCalibrationOptions::radius_factor x
// the search bound; the budget is for crops with the blur stage's border.
std::vector<StoredCrop> StoreBestCrops(
    const WorkingView& working,
    const std::vector<PatchCandidate>& candidates,
    const std::vector<PatchSample>& samples,
    const std::vector<int>& top,
    const std::vector<int>& sample_candidate,
    const DPPsfField& field,
    const PatchGeometry& geometry,
    int border,
    const DPScaleOptions& options);

}  // namespace dpsfm
