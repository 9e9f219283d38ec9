#include "dpsfm/core/scale/view_patches.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>

#include <opencv2/imgproc.hpp>

#include "dpsfm/core/optics/kernel_grid.h"
#include "dpsfm/core/util/check.h"
#include "dpsfm/core/util/fields.h"
#include "dpsfm/core/util/statistics.h"
#include "dpsfm/core/util/threads.h"

namespace dpsfm {

void CheckViewInput(const DPView& view) {
  const std::string& name = view.name;
  DPSFM_CHECK(!view.left.empty() && !view.right.empty())
      << "view '" << name << "': empty DP image";
  DPSFM_CHECK(view.left.size() == view.right.size() &&
              view.left.type() == view.right.type())
      << "view '" << name << "': left and right differ in size or type";
  DPSFM_CHECK(view.left.type() == CV_32FC1 || view.left.type() == CV_32FC3)
      << "view '" << name << "': DP images must be CV_32FC1 or CV_32FC3";
  DPSFM_CHECK(view.lens.Check())
      << "view '" << name << "': invalid lens data (" << view.lens.ToString()
      << "): " << OptionCheckFailure(view.lens);
  DPSFM_CHECK(!view.depth.empty() || !view.depth_points.empty())
      << "view '" << name << "': neither a depth map nor depth points";
  DPSFM_CHECK(view.depth.empty() || view.depth.type() == CV_32FC1)
      << "view '" << name << "': depth map must be CV_32FC1";
}

PatchGeometry ViewPatchGeometry(const cv::Size& frame_size,
                                const DPScaleOptions& options) {
  PatchGeometry geometry =
      options.geometry.resize_factor > 0
          ? DefaultPatchGeometry(frame_size, options.geometry.resize_factor)
          : DefaultPatchGeometry(frame_size);
  // An explicit bound keeps the patches the automatic one starts with: it
  // sets how far the search reaches, not which patches there are.
  if (geometry.max_radius_px < options.geometry.min_auto_radius_px) {
    geometry = PatchGeometryForRadius(options.geometry.min_auto_radius_px,
                                      geometry.resize_factor);
  }
  if (options.geometry.patch_size > 0)
    geometry.patch_size = options.geometry.patch_size;
  if (options.geometry.stride > 0) geometry.stride = options.geometry.stride;
  if (options.geometry.max_radius_px > 0)
    geometry.max_radius_px = options.geometry.max_radius_px;
  return geometry;
}

cv::Size FrameSize(const DPView& view) {
  return view.frame_size.empty() ? view.left.size() : view.frame_size;
}

namespace {

cv::Size WorkingSize(const cv::Size& frame, double resize_factor) {
  if (!(resize_factor < 1)) return frame;
  return {
      std::max(1, static_cast<int>(std::round(frame.width * resize_factor))),
      std::max(1, static_cast<int>(std::round(frame.height * resize_factor)))};
}

}  // namespace

cv::Mat WorkingFrame(const cv::Mat& frame, double resize_factor) {
  const cv::Size size = WorkingSize(frame.size(), resize_factor);
  if (size == frame.size()) return frame;
  cv::Mat working;
  cv::resize(frame, working, size, 0, 0, cv::INTER_AREA);
  return working;
}

int WorkingFrameStripRows(const cv::Size& frame, double resize_factor) {
  if (!(resize_factor < 1)) return 0;
  const long k = std::lround(1 / resize_factor);
  if (k < 2 || std::abs(k * resize_factor - 1) > 1e-12) return 0;
  const cv::Size working = WorkingSize(frame, resize_factor);
  if (working.width * k != frame.width || working.height * k != frame.height) {
    return 0;
  }
  return static_cast<int>(k);
}

WorkingView MakeWorkingView(const DPView& view, double resize_factor) {
  const cv::Size frame = FrameSize(view);
  WorkingView working;
  if (view.frame_size.empty()) {
    working.left = WorkingFrame(view.left, resize_factor);
    working.right = WorkingFrame(view.right, resize_factor);
  } else {
    DPSFM_CHECK(view.left.size() == WorkingSize(frame, resize_factor))
        << "view '" << view.name << "': frames of " << view.left.cols << "x"
        << view.left.rows << " are not the " << frame.width << "x"
        << frame.height << " frame reduced by " << resize_factor;
    working.left = view.left;
    working.right = view.right;
  }
  working.sx = static_cast<double>(working.left.cols) / frame.width;
  working.sy = static_cast<double>(working.left.rows) / frame.height;
  working.gray_left = ToLuma(working.left);
  working.gray_right = ToLuma(working.right);
  return working;
}

int BlurSearchBorder(const DPPsfField& field,
                     const BlurEstimationOptions& blur,
                     double max_radius_px) {
  const double grid_bound = DPKernelGridBound(max_radius_px, blur.grid_step_px);
  int border = 0;
  for (const auto& psf : field.cells) {
    border = std::max(border, psf->KernelRadius(grid_bound));
  }
  return border;
}

int PatchCell(const DPPsfField& field,
              const cv::Rect& interior,
              const cv::Size& working_size) {
  return field.layout.CellAt(
      (interior.x + 0.5 * interior.width) / working_size.width,
      (interior.y + 0.5 * interior.height) / working_size.height);
}

std::vector<PatchCandidate> PatchesWithDepth(const DPView& view,
                                             const WorkingView& working,
                                             const PatchGeometry& geometry,
                                             int border,
                                             const DPScaleOptions& options) {
  std::vector<PatchCandidate> candidates = MakePatchGrid(
      working.left.size(), geometry.patch_size, geometry.stride, border);
  PatchDepthOptions depth_options;
  depth_options.min_coverage = options.patches.min_depth_coverage;
  depth_options.min_points = options.patches.min_depth_points_per_patch;
  depth_options.max_relative_spread = options.patches.max_relative_depth_spread;
  depth_options.num_threads = options.num_threads;
  MeasurePatchDepths(view.depth,
                     view.depth_points,
                     FrameSize(view),
                     working.sx,
                     working.sy,
                     depth_options,
                     &candidates);
  return candidates;
}

BlurSearchEstimators::BlurSearchEstimators(const DPPsfField& field,
                                           int num_threads)
    : field_(field), num_threads_(num_threads) {}

std::shared_ptr<const BlurSearchEstimators::Estimators>
BlurSearchEstimators::For(const BlurEstimationOptions& blur, int crop) {
  auto it = std::find_if(
      geometries_.begin(), geometries_.end(), [&](const Geometry& g) {
        return g.crop == crop && SameFields(g.blur, blur);
      });
  if (it != geometries_.end()) {
    std::rotate(it, it + 1, geometries_.end());  // most recently used last
    return geometries_.back().estimators;
  }
  if (static_cast<int>(geometries_.size()) >= kMaxGeometries) {
    geometries_.erase(geometries_.begin());
  }
  auto estimators = std::make_shared<Estimators>();
  for (const auto& psf : field_.cells) {
    estimators->emplace_back(
        new PatchBlurEstimator(*psf, blur, cv::Size(crop, crop), num_threads_));
    ++num_built_;
  }
  geometries_.push_back({crop, blur, estimators});
  return estimators;
}

ViewBlurSearch ChooseViewSearch(const WorkingView& working,
                                const std::vector<PatchCandidate>& candidates,
                                int border,
                                bool any_depth,
                                const DPScaleOptions& options) {
  const int num = static_cast<int>(candidates.size());
  ViewBlurSearch out;
  out.estimates.resize(num);
  if (any_depth) {
    out.screened = ScreenPatches(working.gray_left,
                                 working.gray_right,
                                 candidates,
                                 border,
                                 options.patches.min_texture_snr,
                                 options.num_threads,
                                 &out.estimates);
  }
  SearchShareOptions share;
  share.blur_search_factor = options.patches.blur_search_factor;
  share.top_patch_fraction = options.patches.top_patch_fraction;
  share.min_patches_per_view = options.patches.min_patches_per_view;
  share.depth_strata = options.patches.depth_strata;
  out.chosen = ChooseSearchedPatches(out.screened, num, share, &out.estimates);
  out.searched.assign(num, 0);
  return out;
}

void SearchChosenPatches(const WorkingView& working,
                         const std::vector<PatchCandidate>& candidates,
                         const DPPsfField& field,
                         const BlurEstimationOptions& blur,
                         int border,
                         int patch_size,
                         const DPScaleOptions& options,
                         BlurSearchEstimators* cache,
                         const std::vector<char>* which,
                         ViewBlurSearch* search) {
  const int num = static_cast<int>(candidates.size());
  std::vector<int> todo;
  for (int k = 0; k < num; ++k) {
    if (search->chosen[k] && !search->searched[k] &&
        (which == nullptr || (*which)[k])) {
      todo.push_back(k);
    }
  }
  if (todo.empty()) return;
  const std::shared_ptr<const BlurSearchEstimators::Estimators> held =
      cache->For(blur, patch_size + 2 * border);
  const BlurSearchEstimators::Estimators& estimators = *held;
  DPSFM_INVARIANT(estimators.size() == field.cells.size());
  for (const auto& estimator : estimators) {
    DPSFM_INVARIANT(estimator->Border() <= border);
  }
  std::vector<PatchBlurEstimate>& estimates = search->estimates;
  const int num_todo = static_cast<int>(todo.size());
  // A patch the estimator cannot take (a failed DPSFM_CHECK) is rejected
  // with its reason; anything else (an invariant, no memory) ends the run
  // after the loop (ParallelFor).
  ParallelFor(num_todo, options.num_threads, [&](int i) {
    const int k = todo[i];
    const cv::Rect& interior = candidates[k].interior;
    const cv::Rect r = PatchCrop(interior, border);
    try {
      estimates[k] =
          estimators[PatchCell(field, interior, working.left.size())]->Estimate(
              working.gray_left(r).clone(), working.gray_right(r).clone());
    } catch (const CheckFailure& e) {
      estimates[k].valid = false;
      estimates[k].reject_reason = e.what();
    }
  });
  for (const int k : todo) search->searched[k] = 1;
  search->num_searched += num_todo;
}

std::vector<char> GrowthSample(const ViewBlurSearch& search) {
  std::vector<char> sample(search.chosen.size(), 0);
  int rank = 0, taken = 0;
  for (size_t k = 0; k < search.chosen.size(); ++k) {
    if (search.chosen[k] && rank++ % kGrowthSampleStep == 0) {
      sample[k] = 1;
      ++taken;
    }
  }
  if (taken < kMinGrowthSample) sample.assign(sample.size(), 0);
  return sample;
}

int PatchesAtSearchBound(const ViewBlurSearch& search) {
  int count = 0;
  for (const PatchBlurEstimate& e : search.estimates) {
    count += e.evidence == BlurEvidence::kBeyondBound;
  }
  return count;
}

double LargerSearchBound(double bound_px) {
  return std::ceil(2 * std::max(1.6 * bound_px, bound_px + 2) - 1e-9) / 2;
}

bool SearchBoundMayGrow(int growths, const DPScaleOptions& options) {
  return options.geometry.max_radius_px <= 0 &&
         growths < options.geometry.max_search_bound_growths;
}

bool SearchBoundReached(int num_searched,
                        int num_at_bound,
                        int growths,
                        const DPScaleOptions& options) {
  return SearchBoundMayGrow(growths, options) && num_searched > 0 &&
         !(num_at_bound < options.geometry.search_bound_share * num_searched);
}

double SearchBoundCap(double bound_px) {
  return std::ceil(2 * 2 * bound_px - 1e-9) / 2;
}

double GrownSearchBound(const PatchGeometry& geometry,
                        const cv::Size& working_size,
                        const DPPsfField& field,
                        const BlurEstimationOptions& blur) {
  // At most twice the bound: the search's cost grows with the bound (its
  // kernel grid and crops), and uncapped growth to 20-36 px on the
  // generated tabletops cost 3-4x the blur stage; patches beyond stay
  // beyond, and the run says so. Not the blur a line through the usable
  // patches expects: a 0.5 px step of that line moved answers by 3 %.
  for (const double grown : {SearchBoundCap(geometry.max_radius_px),
                             LargerSearchBound(geometry.max_radius_px)}) {
    const int crop =
        geometry.patch_size + 2 * BlurSearchBorder(field, blur, grown);
    if (2 * crop <= std::min(working_size.width, working_size.height)) {
      return grown;
    }
  }
  return 0;
}

double EarlyGrownSearchBound(int num_searched,
                             int num_beyond_bound,
                             int growths,
                             const PatchGeometry& geometry,
                             const cv::Size& working_size,
                             const DPPsfField& field,
                             const BlurEstimationOptions& blur,
                             const DPScaleOptions& options) {
  if (!SearchBoundReached(num_searched, num_beyond_bound, growths, options)) {
    return 0;
  }
  const double p = options.geometry.search_bound_share;
  const double standard_error = std::sqrt(p * (1 - p) / num_searched);
  if (num_beyond_bound < (p + 2 * standard_error) * num_searched) return 0;
  return GrownSearchBound(geometry, working_size, field, blur);
}

std::vector<PatchSample> ViewSamples(
    const std::vector<PatchCandidate>& candidates,
    const ViewBlurSearch& search,
    const WorkingView& working,
    const DPPsfField& field,
    const PatchGeometry& geometry,
    int view_index,
    const DPScaleOptions& options,
    std::map<std::string, int>* rejections,
    std::vector<int>* sample_candidate) {
  const double residual_threshold =
      ViewResidualThreshold(candidates,
                            search.estimates,
                            options.patches.max_relative_residual,
                            options.patches.relative_residual_factor);
  const int p = geometry.patch_size;
  std::vector<PatchSample> samples;
  for (size_t k = 0; k < candidates.size(); ++k) {
    const PatchCandidate& c = candidates[k];
    const PatchBlurEstimate& e = search.estimates[k];
    const std::string reject = PatchRejection(
        c, e, options.patches.min_texture_snr, residual_threshold);
    if (!reject.empty()) {
      (*rejections)[reject]++;
      continue;
    }
    sample_candidate->push_back(static_cast<int>(k));
    PatchSample s;
    s.view = view_index;
    s.psf_band = PatchCell(field, c.interior, working.left.size());
    const double cx = c.interior.x + 0.5 * (p - 1);
    const double cy = c.interior.y + 0.5 * (p - 1);
    s.x = (cx + 0.5) / working.sx - 0.5;
    s.y = (cy + 0.5) / working.sy - 0.5;
    s.depth = c.depth.median;
    s.depth_spread = c.depth.relative_spread;
    s.radius_px = e.radius_px;
    s.radius_se_px = e.radius_se_px;
    s.radius_frame_px = e.radius_px / geometry.resize_factor;
    s.fit_quality = e.fit_quality;
    s.texture = e.texture;
    s.texture_snr = TextureSnr(e.texture, e.noise_sigma);
    s.confidence =
        PatchConfidence(e.texture, e.fit_quality, c.depth.relative_variance);
    s.predicted_radius_px = std::numeric_limits<double>::quiet_NaN();
    samples.push_back(s);
  }
  return samples;
}

std::vector<int> SelectTopSamples(const std::vector<PatchSample>& samples,
                                  const ViewBlurSearch& search,
                                  const DPScaleOptions& options) {
  std::vector<double> confidence, inverse_depth;
  for (const PatchSample& s : samples) {
    confidence.push_back(s.confidence);
    inverse_depth.push_back(1.0 / s.depth);
  }
  const double keep_fraction =
      search.num_searched > 0
          ? std::min(1.0,
                     options.patches.top_patch_fraction *
                         search.screened.index.size() / search.num_searched)
          : options.patches.top_patch_fraction;
  return SelectTopFractionStratified(confidence,
                                     inverse_depth,
                                     keep_fraction,
                                     options.patches.min_patches_per_view,
                                     options.patches.depth_strata);
}

std::vector<StoredCrop> StoreBestCrops(
    const WorkingView& working,
    const std::vector<PatchCandidate>& candidates,
    const std::vector<PatchSample>& samples,
    const std::vector<int>& top,
    const std::vector<int>& sample_candidate,
    const DPPsfField& field,
    const PatchGeometry& geometry,
    int border,
    const DPScaleOptions& options) {
  std::vector<int> by_confidence = top;
  std::stable_sort(
      by_confidence.begin(), by_confidence.end(), [&](int a, int b) {
        return samples[a].confidence > samples[b].confidence;
      });
  int store_border = border;
  if (options.self_calibration.mode != SelfCalibrationOptions::Mode::kOff) {
    for (const auto& psf : field.cells) {
      store_border = std::max(
          store_border,
          psf->KernelRadius(options.self_calibration.radius_factor *
                            DPKernelGridBound(geometry.max_radius_px,
                                              options.blur.grid_step_px)));
    }
  }
  const int crop = geometry.patch_size + 2 * border;
  const int cap = MaxStoredCrops(crop,
                                 working.left.channels(),
                                 options.patches.max_stored_patches_per_view,
                                 options.patches.max_stored_megabytes_per_view);
  if (static_cast<int>(by_confidence.size()) > cap) by_confidence.resize(cap);
  std::vector<std::pair<int, cv::Rect>> to_store;
  for (int i : by_confidence) {
    to_store.emplace_back(i, candidates[sample_candidate[i]].interior);
  }
  return StoreCrops(
      working.left, working.right, to_store, border, store_border);
}

}  // namespace dpsfm
