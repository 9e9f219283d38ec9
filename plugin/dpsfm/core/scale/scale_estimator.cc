#include "dpsfm/core/scale/scale_estimator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "dpsfm/core/blur/crop_store.h"
#include "dpsfm/core/blur/patch_grid.h"
#include "dpsfm/core/blur/patch_selection.h"
#include "dpsfm/core/optics/kernel_grid.h"
#include "dpsfm/core/scale/refusal.h"
#include "dpsfm/core/util/check.h"
#include "dpsfm/core/util/curve_math.h"
#include "dpsfm/core/util/statistics.h"
#include "dpsfm/core/util/threads.h"

namespace dpsfm {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start)
      .count();
}

double TextureSnr(const PatchBlurEstimate& e) {
  return dpsfm::TextureSnr(e.texture, e.noise_sigma);
}

// Whether `value` lies in [lo, hi] widened by a relative systematic term
// (in quadrature with each half).
bool IntervalContains(
    double centre, double lo, double hi, double relative, double value) {
  const double sys = relative * centre;
  const double dl = std::max(0.0, centre - lo), dh = std::max(0.0, hi - centre);
  return value >= centre - std::sqrt(dl * dl + sys * sys) &&
         value <= centre + std::sqrt(dh * dh + sys * sys);
}

}  // namespace

bool DPScaleOptions::Check() const {
  DPSFM_CHECK_OPTION_GE(patch_size, 0);
  DPSFM_CHECK_OPTION_GE(stride, 0);
  DPSFM_CHECK_OPTION_GE(max_radius_px, 0);
  DPSFM_CHECK_OPTION_GE(min_auto_radius_px, 0);
  // 0 is automatic.
  DPSFM_CHECK_OPTION_VALUE(resize_factor >= 0 && resize_factor <= 1,
                           resize_factor);
  DPSFM_CHECK_OPTION_VALUE(top_patch_fraction > 0 && top_patch_fraction <= 1,
                           top_patch_fraction);
  DPSFM_CHECK_OPTION_GE(min_patches_per_view, 0);
  DPSFM_CHECK_OPTION_GE(depth_strata, 1);
  DPSFM_CHECK_OPTION_GE(blur_search_factor, 0);
  DPSFM_CHECK_OPTION_GE(max_stored_patches_per_view, 0);
  DPSFM_CHECK_OPTION_GE(max_stored_megabytes_per_view, 0);
  DPSFM_CHECK_OPTION_VALUE(min_depth_coverage > 0 && min_depth_coverage <= 1,
                           min_depth_coverage);
  DPSFM_CHECK_OPTION_GE(min_depth_points_per_patch, 1);
  DPSFM_CHECK_OPTION_GT(max_relative_depth_spread, 0);
  DPSFM_CHECK_OPTION_GE(min_texture_snr, 0);
  DPSFM_CHECK_OPTION_GE(max_relative_residual, 0);
  DPSFM_CHECK_OPTION_GE(relative_residual_factor, 0);
  DPSFM_CHECK_OPTION_GT(max_intensity_ci_relative_width, 0);
  DPSFM_CHECK_OPTION_GT(max_scale_ci_relative_width, 0);
  DPSFM_CHECK_OPTION_GE(recorded_focus_tolerance, 0);
  DPSFM_CHECK_OPTION_VALUE(self_calibration_shape_uncertainty >= 0 &&
                               self_calibration_shape_uncertainty < 1,
                           self_calibration_shape_uncertainty);
  DPSFM_CHECK_OPTION_GE(min_total_patches, 0);
  DPSFM_CHECK_OPTION_GE(scale_systematic_uncertainty, 0);
  DPSFM_CHECK_OPTION_GE(lens_geometry_uncertainty, 0);
  DPSFM_CHECK_OPTION_VALUE(
      profile_relative_uncertainty >= 0 && profile_relative_uncertainty < 1,
      profile_relative_uncertainty);
  DPSFM_CHECK_OPTION_VALUE(min_intensity_bootstrap_support >= 0 &&
                               min_intensity_bootstrap_support <= 1,
                           min_intensity_bootstrap_support);
  DPSFM_CHECK_OPTION_VALUE(num_threads == -1 || num_threads > 0, num_threads);
  DPSFM_CHECK_OPTION_GE(max_psf_fit_patches, 1);
  DPSFM_CHECK_OPTION_VALUE(
      psf_fit_radius_factor >= 1 && psf_fit_radius_factor <= 4,
      psf_fit_radius_factor);
  DPSFM_CHECK_OPTION_GE(psf_fit_bands, 1);
  DPSFM_CHECK_OPTION_GE(max_psf_fit_depth_spread, 0);
  if (psf_self_calibration) {
    DPSFM_CHECK_NESTED_OPTIONS(psf_fit);
  }
  DPSFM_CHECK_NESTED_OPTIONS(blur);
  DPSFM_CHECK_NESTED_OPTIONS(linear);
  DPSFM_CHECK_NESTED_OPTIONS(intensity);
  return true;
}

struct DPScaleEstimator::ViewData {
  DPViewSummary summary;
  DPLensData lens;
  double working_pitch_mm = 0;
  std::vector<PatchSample> samples;  // valid patches only
  std::vector<StoredCrop> stored;    // best selected patches (crop_store.h)
};

// The terms that widen a statistical scale interval: the estimator's
// systematic term and the lens geometry's (relative, in quadrature), then
// the DP profile's own uncertainty (factors on the bounds).
struct DPScaleEstimator::IntervalTerms {
  double systematic = 0;
  double lens_geometry = 0;
  double profile_low = 1, profile_high = 1;

  void Widen(double s, double* lo, double* hi) const {
    const double sys = std::hypot(systematic, lens_geometry) * s;
    const double dl = std::max(0.0, s - *lo), dh = std::max(0.0, *hi - s);
    *lo = s - std::sqrt(dl * dl + sys * sys);
    *hi = s + std::sqrt(dh * dh + sys * sys);
  }
  void ApplyProfile(double* lo, double* hi) const {
    *lo *= profile_low;
    *hi *= profile_high;
  }
};

DPScaleEstimator::DPScaleEstimator(const DPScaleOptions& options,
                                   std::shared_ptr<const DPPsfModel> psf)
    : DPScaleEstimator(options, DPPsfField::Uniform(std::move(psf))) {}

DPScaleEstimator::DPScaleEstimator(const DPScaleOptions& options,
                                   DPPsfField field)
    : options_(options), field_(std::move(field)) {
  DPSFM_CHECK_OPTIONS(options_, "DPScaleOptions");
  field_.CheckValid();
  DPSFM_CHECK(field_.cells.size() == 1 || !options_.psf_self_calibration)
      << "self-calibration fits one profile for the whole frame";
  psf_ = field_.cells[0];
}

DPScaleEstimator::~DPScaleEstimator() = default;

int DPScaleEstimator::NumViews() const {
  return static_cast<int>(views_.size());
}

DPViewSummary DPScaleEstimator::AddView(const DPView& view) {
  const auto start = std::chrono::steady_clock::now();
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
      << "): " << OptionCheckFailure();
  DPSFM_CHECK(!view.depth.empty() || !view.depth_points.empty())
      << "view '" << name << "': neither a depth map nor depth points";
  DPSFM_CHECK(view.depth.empty() || view.depth.type() == CV_32FC1)
      << "view '" << name << "': depth map must be CV_32FC1";

  std::unique_ptr<ViewData> data(new ViewData);
  DPViewSummary& summary = data->summary;
  summary.name = name;
  summary.frames = view.frames;
  summary.index = static_cast<int>(views_.size());
  summary.frame_size = view.left.size();
  data->lens = view.lens;

  // Geometry: reference defaults for the frame size, then explicit options.
  PatchGeometry geometry =
      options_.resize_factor > 0
          ? DefaultPatchGeometry(view.left.size(), options_.resize_factor)
          : DefaultPatchGeometry(view.left.size());
  if (options_.max_radius_px <= 0 &&
      geometry.max_radius_px < options_.min_auto_radius_px) {
    geometry = PatchGeometryForRadius(options_.min_auto_radius_px,
                                      geometry.resize_factor);
  }
  if (options_.patch_size > 0) geometry.patch_size = options_.patch_size;
  if (options_.stride > 0) geometry.stride = options_.stride;
  if (options_.max_radius_px > 0)
    geometry.max_radius_px = options_.max_radius_px;
  const double rf = geometry.resize_factor;
  summary.resize_factor = rf;
  summary.patch_size = geometry.patch_size;
  summary.stride = geometry.stride;
  summary.max_radius_px = geometry.max_radius_px;
  data->working_pitch_mm = view.lens.PixelPitchMm() / rf;

  cv::Mat left = view.left, right = view.right;
  if (rf < 1) {
    // Area averaging is the anti-aliased resize the reference code uses.
    const cv::Size size(
        std::max(1, static_cast<int>(std::round(view.left.cols * rf))),
        std::max(1, static_cast<int>(std::round(view.left.rows * rf))));
    cv::resize(view.left, left, size, 0, 0, cv::INTER_AREA);
    cv::resize(view.right, right, size, 0, 0, cv::INTER_AREA);
  }
  summary.working_size = left.size();
  // Frame <-> working scale per axis (exact for the rounded size).
  const double sx = static_cast<double>(left.cols) / view.left.cols;
  const double sy = static_cast<double>(left.rows) / view.left.rows;
  const cv::Mat gray_left = ToLuma(left), gray_right = ToLuma(right);

  BlurEstimationOptions blur = options_.blur;
  blur.max_radius_px = geometry.max_radius_px;
  // The border the blur search's kernel grid needs (its bound is the
  // search bound rounded up to a grid step).
  const double grid_bound =
      DPKernelGrid::BoundFor(blur.grid_step_px, geometry.max_radius_px);
  int border = 0;
  for (const auto& psf : field_.cells) {
    border = std::max(border, psf->KernelRadius(grid_bound));
  }
  auto band_of = [&](const cv::Rect& interior) {
    return field_.layout.CellAt(
        (interior.x + 0.5 * interior.width) / left.cols,
        (interior.y + 0.5 * interior.height) / left.rows);
  };
  const int p = geometry.patch_size;
  const int crop = p + 2 * border;
#ifdef _OPENMP
  const int threads = EffectiveNumThreads(options_.num_threads);
#endif

  // 1. The patch grid and each patch's depth (patch_grid.h).
  std::vector<PatchCandidate> candidates =
      MakePatchGrid(left.size(), p, geometry.stride, border);
  summary.patches_tried = static_cast<int>(candidates.size());
  PatchDepthOptions depth_options;
  depth_options.min_coverage = options_.min_depth_coverage;
  depth_options.min_points = options_.min_depth_points_per_patch;
  depth_options.max_relative_spread = options_.max_relative_depth_spread;
  MeasurePatchDepths(view.depth,
                     view.depth_points,
                     view.left.size(),
                     sx,
                     sy,
                     depth_options,
                     &candidates);
  const int num = static_cast<int>(candidates.size());
  for (const PatchCandidate& c : candidates) {
    summary.patches_with_depth += c.reject.empty();
  }

  // 2. Screening and the blur-search share (patch_selection.h).
  std::vector<PatchBlurEstimate> estimates(num);
  ScreenedPatches screened;
  if (summary.patches_with_depth > 0) {
    screened = ScreenPatches(gray_left,
                             gray_right,
                             candidates,
                             border,
                             options_.min_texture_snr,
                             options_.num_threads,
                             &estimates);
  }
  SearchShareOptions share;
  share.blur_search_factor = options_.blur_search_factor;
  share.top_patch_fraction = options_.top_patch_fraction;
  share.min_patches_per_view = options_.min_patches_per_view;
  share.depth_strata = options_.depth_strata;
  const std::vector<char> search =
      ChooseSearchedPatches(screened, num, share, &estimates);
  const int num_searched =
      static_cast<int>(std::count(search.begin(), search.end(), 1));
  summary.patches_searched = num_searched;

  // 3. The blur search on the chosen patches (the expensive part), in
  // parallel.
  if (num_searched > 0) {
    std::vector<std::unique_ptr<PatchBlurEstimator>> estimators;
    for (const auto& psf : field_.cells) {
      estimators.emplace_back(
          new PatchBlurEstimator(*psf, blur, cv::Size(crop, crop)));
      DPSFM_CHECK_LE(estimators.back()->Border(), border);
    }
#ifdef _OPENMP
#pragma omp parallel for num_threads(threads) schedule(dynamic)
#endif
    for (int k = 0; k < num; ++k) {
      if (!search[k]) continue;
      const cv::Rect& interior = candidates[k].interior;
      const cv::Rect r = PatchCrop(interior, border);
      try {
        estimates[k] = estimators[band_of(interior)]->Estimate(
            gray_left(r).clone(), gray_right(r).clone());
      } catch (const std::exception& e) {
        estimates[k].valid = false;
        estimates[k].reject_reason = e.what();
      }
    }
  }

  // 4. Usable patches become samples; the others are counted by reason.
  const double residual_threshold =
      ViewResidualThreshold(candidates,
                            estimates,
                            options_.max_relative_residual,
                            options_.relative_residual_factor);
  std::map<std::string, int> rejections;
  std::vector<int> sample_candidate;  // grid index of each sample
  for (int k = 0; k < num; ++k) {
    const PatchCandidate& c = candidates[k];
    const PatchBlurEstimate& e = estimates[k];
    const std::string reject =
        PatchRejection(c, e, options_.min_texture_snr, residual_threshold);
    if (!reject.empty()) {
      rejections[reject]++;
      continue;
    }
    sample_candidate.push_back(k);
    PatchSample s;
    s.view = summary.index;
    s.psf_band = band_of(c.interior);
    const double cx = c.interior.x + 0.5 * (p - 1);
    const double cy = c.interior.y + 0.5 * (p - 1);
    s.x = (cx + 0.5) / sx - 0.5;
    s.y = (cy + 0.5) / sy - 0.5;
    s.depth = c.depth.median;
    s.depth_spread = c.depth.relative_spread;
    s.radius_px = e.radius_px;
    s.radius_frame_px = e.radius_px / rf;
    s.fit_quality = e.fit_quality;
    s.texture = e.texture;
    s.texture_snr = TextureSnr(e);
    // Reference confidence sobel * exp(-1e6 loss) / (var(depth) + 1e-10),
    // with the blur estimator's fit quality in place of exp(-1e6 loss) (which
    // underflows at real noise levels) and the RELATIVE depth variance (scale
    // free) floored at 1 % std, so that depth noise below that level does not
    // decide the ranking.
    s.confidence = std::max(e.texture, 0.0) * std::max(e.fit_quality, 0.0) /
                   (c.depth.relative_variance + 1e-4);
    s.predicted_radius_px = kNaN;
    data->samples.push_back(s);
  }
  summary.patches_valid = static_cast<int>(data->samples.size());
  for (const auto& r : rejections) summary.rejections.emplace_back(r);

  // 5. Top-T_c selection (of all screened patches, taken from the searched
  // ones; all of them when blur_search_factor is 0).
  std::vector<double> confidence, inverse_depth;
  for (const PatchSample& s : data->samples) {
    confidence.push_back(s.confidence);
    inverse_depth.push_back(1.0 / s.depth);
  }
  const double keep_fraction =
      num_searched > 0 ? std::min(1.0,
                                  options_.top_patch_fraction *
                                      screened.index.size() / num_searched)
                       : options_.top_patch_fraction;
  const std::vector<int> top =
      SelectTopFractionStratified(confidence,
                                  inverse_depth,
                                  keep_fraction,
                                  options_.min_patches_per_view,
                                  options_.depth_strata);
  for (int i : top) data->samples[i].selected = true;
  summary.patches_kept = static_cast<int>(top.size());

  // 6. Crops of the best selected patches for the intensity stage and
  // self-calibration (crop_store.h), best first. With self-calibration
  // their border supports blur up to psf_fit_radius_factor x the search
  // bound (see the option). The budget is for crops with the blur stage's
  // border: the wider border self-calibration needs does not cost patches.
  std::vector<int> by_confidence = top;
  std::stable_sort(by_confidence.begin(),
                   by_confidence.end(),
                   [&](int a, int b) { return confidence[a] > confidence[b]; });
  int store_border = border;
  if (options_.psf_self_calibration) {
    for (const auto& psf : field_.cells) {
      store_border = std::max(
          store_border,
          psf->KernelRadius(options_.psf_fit_radius_factor *
                            DPKernelGridBound(geometry.max_radius_px,
                                              options_.blur.grid_step_px)));
    }
  }
  const int cap = MaxStoredCrops(crop,
                                 left.channels(),
                                 options_.max_stored_patches_per_view,
                                 options_.max_stored_megabytes_per_view);
  if (static_cast<int>(by_confidence.size()) > cap) by_confidence.resize(cap);
  std::vector<std::pair<int, cv::Rect>> to_store;
  for (int i : by_confidence) {
    to_store.emplace_back(i, candidates[sample_candidate[i]].interior);
  }
  data->stored = StoreCrops(left, right, to_store, border, store_border);

  summary.seconds = SecondsSince(start);
  views_.push_back(std::move(data));
  return summary;
}

void DPScaleEstimator::CalibrateProfile(
    std::vector<std::vector<PatchSample>>* samples,
    DPPsfField* field,
    DPScaleResult* result) const {
  // Stored crops by geometry (crop size, radius bound): FitSplitProfile
  // takes one geometry; the largest group feeds it.
  struct Ref {
    int view, stored;
  };
  std::map<std::pair<int, double>, std::vector<Ref>> groups;
  for (int i = 0; i < static_cast<int>(views_.size()); ++i) {
    const ViewData& v = *views_[i];
    for (int k = 0; k < static_cast<int>(v.stored.size()); ++k) {
      groups[{v.stored[k].left.cols, v.summary.max_radius_px}].push_back(
          {i, k});
    }
  }
  auto gray_of = [](const cv::Mat& crop) {
    cv::Mat f;
    crop.convertTo(f, CV_MAKETYPE(CV_32F, crop.channels()), 1.0 / 65535.0);
    return ToLuma(f);
  };
  const std::vector<Ref>* largest = nullptr;
  double bound = 0;
  for (const auto& g : groups) {
    if (largest == nullptr || g.second.size() > largest->size()) {
      largest = &g.second;
      bound = g.first.second;
    }
  }
  if (largest == nullptr) {
    result->psf_status =
        "self-calibration could not determine the DP profile (no stored "
        "patch to fit it to: no view had usable texture and depth); " +
        psf_->Name() + " kept";
    return;
  }
  SplitProfileFitOptions fit_options = options_.psf_fit;
  fit_options.blur = options_.blur;
  fit_options.blur.max_radius_px = options_.psf_fit_radius_factor * bound;
  fit_options.num_threads = options_.num_threads;
  fit_options.seed = options_.seed;
  std::vector<ProfilePatch> patches;
  if (largest != nullptr) {
    // The flat ones (see max_psf_fit_depth_spread), evenly over the views.
    std::vector<Ref> flat;
    std::vector<std::pair<double, size_t>> by_spread;
    for (size_t k = 0; k < largest->size(); ++k) {
      const Ref& ref = (*largest)[k];
      const ViewData& v = *views_[ref.view];
      const double spread = v.samples[v.stored[ref.stored].sample].depth_spread;
      by_spread.emplace_back(spread, k);
      if (spread <= options_.max_psf_fit_depth_spread) flat.push_back(ref);
    }
    const size_t enough = 2 * static_cast<size_t>(fit_options.min_patches);
    if (flat.size() < enough) {
      std::stable_sort(by_spread.begin(), by_spread.end());
      flat.clear();
      for (size_t i = 0; i < by_spread.size() && i < enough; ++i) {
        flat.push_back((*largest)[by_spread[i].second]);
      }
      std::sort(flat.begin(), flat.end(), [](const Ref& a, const Ref& b) {
        return a.view != b.view ? a.view < b.view : a.stored < b.stored;
      });
    }
    const size_t step =
        std::max<size_t>(1,
                         (flat.size() + options_.max_psf_fit_patches - 1) /
                             options_.max_psf_fit_patches);
    for (size_t k = 0; k < flat.size(); k += step) {
      const StoredCrop& st = views_[flat[k].view]->stored[flat[k].stored];
      ProfilePatch patch;
      patch.left = gray_of(st.left);
      patch.right = gray_of(st.right);
      const ViewData& v = *views_[flat[k].view];
      patch.x_fraction =
          (v.samples[st.sample].x + 0.5) / v.summary.frame_size.width;
      patches.push_back(patch);
    }
  }
  SplitProfileCalibration calibration;
  try {
    calibration = CalibrateSplitProfile(patches,
                                        options_.psf_fit_bands,
                                        fit_options,
                                        0.02,
                                        /*bands_when_frame_fits=*/false);
  } catch (const std::exception& e) {
    calibration.summary = e.what();
  }
  result->psf_fit = calibration.frame;
  const SplitProfileFit& fit = calibration.frame;
  std::ostringstream status;
  // The profiles to use: one for the whole frame, or one per band (a band
  // may keep the translating disk).
  std::vector<std::shared_ptr<const DPPsfModel>> fitted;
  auto profile_of =
      [&](const SplitProfileFit& f) -> std::shared_ptr<const DPPsfModel> {
    if (f.translating_disk) return std::make_shared<TranslatingDiskPsf>();
    return std::make_shared<SplitProfilePsf>(f.params);
  };
  if (calibration.banded) {
    result->psf_band_fits = calibration.bands;
    for (const SplitProfileFit& band : calibration.bands) {
      fitted.push_back(profile_of(band));
    }
  } else if (!fit.determined) {
    status << "self-calibration could not determine the DP profile ("
           << calibration.summary << "); " << psf_->Name() << " kept";
    result->psf_status = status.str();
    return;
  } else if (fit.translating_disk) {
    status << "self-calibration kept the translating disk (" << fit.reason
           << ")";
    result->psf_status = status.str();
    return;
  } else {
    fitted.push_back(profile_of(fit));
  }
  DPPsfField fitted_field;
  fitted_field.layout =
      DPPsfLayout::ColumnBands(static_cast<int>(fitted.size()));
  fitted_field.cells = fitted;
  // Every stored patch searched again with its fitted profile; the others
  // (estimated with the old one) leave the selection.
  for (auto& view_samples : *samples) {
    for (PatchSample& s : view_samples) {
      s.selected = false;
      const cv::Size frame = views_[s.view]->summary.frame_size;
      s.psf_band = fitted_field.layout.CellAt((s.x + 0.5) / frame.width,
                                              (s.y + 0.5) / frame.height);
    }
  }
  int reestimated = 0;
  for (const auto& g : groups) {
    BlurEstimationOptions blur = options_.blur;
    blur.max_radius_px = options_.psf_fit_radius_factor * g.first.second;
    std::vector<std::unique_ptr<PatchBlurEstimator>> estimators;
    for (const auto& band : fitted) {
      estimators.emplace_back(new PatchBlurEstimator(
          *band, blur, cv::Size(g.first.first, g.first.first)));
    }
    const std::vector<Ref>& refs = g.second;
#ifdef _OPENMP
    const int threads = EffectiveNumThreads(options_.num_threads);
#pragma omp parallel for num_threads(threads) schedule(dynamic) \
    reduction(+ : reestimated)
#endif
    for (int k = 0; k < static_cast<int>(refs.size()); ++k) {
      const ViewData& v = *views_[refs[k].view];
      const StoredCrop& st = v.stored[refs[k].stored];
      PatchSample& s = (*samples)[refs[k].view][st.sample];
      try {
        const PatchBlurEstimate e = estimators[s.psf_band]->Estimate(
            gray_of(st.left), gray_of(st.right));
        if (e.valid && !e.at_bound && std::isfinite(e.radius_px)) {
          s.radius_px = e.radius_px;
          s.radius_frame_px = e.radius_px / v.summary.resize_factor;
          s.fit_quality = e.fit_quality;
          s.selected = true;
          ++reestimated;
        }
      } catch (const std::exception&) {
        // Left out of the selection.
      }
    }
  }
  status << "self-calibrated DP profile: "
         << (calibration.banded ? calibration.summary : fit.reason) << "; "
         << reestimated << " stored patches re-estimated with it";
  result->psf_status = status.str();
  result->psf_self_calibrated = true;
  *field = fitted_field;
}

namespace {

// Scale factors the self-calibrated profile leaves open (see
// DPScaleResult::profile_scale_factor_low): per cell of the field, the
// consistent centroid offsets over the one used (the translating disk's
// when it was kept); the widest over the cells.
void ProfileScaleFactorsOf(const std::vector<SplitProfileFit>& fits,
                           bool fitted_profile_used,
                           double* low,
                           double* high) {
  *low = 1;
  *high = 1;
  for (const SplitProfileFit& fit : fits) {
    const double used = fitted_profile_used && !fit.translating_disk
                            ? fit.centroid_offset
                            : fit.translating_disk_centroid_offset;
    *low = std::min(*low, fit.consistent_low / used);
    *high = std::max(*high, fit.consistent_high / used);
  }
}

}  // namespace

void DPScaleEstimator::ProfileScaleFactors(const DPPsfField& field,
                                           const DPScaleResult& result,
                                           double* low,
                                           double* high) const {
  if (!result.psf_band_fits.empty() && field.cells.size() > 1) {
    ProfileScaleFactorsOf(result.psf_band_fits, true, low, high);
  } else {
    ProfileScaleFactorsOf(
        {result.psf_fit}, result.psf_self_calibrated, low, high);
  }
}

DPScaleResult DPScaleEstimator::Estimate() const {
  DPScaleResult result;
  const int num_views = static_cast<int>(views_.size());
  for (const auto& v : views_) result.seconds_blur += v->summary.seconds;
  if (num_views == 0) {
    result.failure_reason = "no DP views were given";
    return result;
  }

  // The patches as the stages see them, and the PSF they use:
  // self-calibration may replace both.
  std::vector<std::vector<PatchSample>> samples(num_views);
  for (int i = 0; i < num_views; ++i) samples[i] = views_[i]->samples;
  DPPsfField field = field_;
  if (options_.psf_self_calibration && field_.cells.size() == 1) {
    const auto fit_start = std::chrono::steady_clock::now();
    CalibrateProfile(&samples, &field, &result);
    result.seconds_psf_fit = SecondsSince(fit_start);
  }
  const std::shared_ptr<const DPPsfModel> psf = field.cells[0];
  result.psf_model = field.Name();

  // --- Linear stage. ---
  auto start = std::chrono::steady_clock::now();
  std::vector<LinearViewData> linear_views(num_views);
  std::vector<int> selected_count(num_views, 0);
  for (int i = 0; i < num_views; ++i) {
    const ViewData& v = *views_[i];
    linear_views[i].name = v.summary.name;
    linear_views[i].lens = v.lens;
    linear_views[i].pixel_pitch_mm = v.working_pitch_mm;
    for (const PatchSample& s : samples[i]) {
      if (s.selected) {
        linear_views[i].samples.push_back({s.depth, s.radius_px});
        ++selected_count[i];
      }
    }
  }
  LinearEstimatorOptions linear_options = options_.linear;
  linear_options.seed = options_.seed;
  LinearEstimate linear;
  try {
    linear = EstimateScaleLinear(linear_views, linear_options);
  } catch (const std::exception& e) {
    result.failure_reason = std::string("linear stage failed: ") + e.what();
    return result;
  }
  result.seconds_linear = SecondsSince(start);

  result.views.resize(num_views);
  for (int i = 0; i < num_views; ++i) {
    const ViewData& v = *views_[i];
    const LinearViewResult& lv = linear.views[i];
    DPViewResult& out = result.views[i];
    out.name = v.summary.name;
    out.frames = v.summary.frames;
    out.lens = v.lens;
    out.recorded_focus_m = v.lens.recorded_focus_mm / 1000;  // NaN if none
    out.used = lv.used;
    out.reason = lv.reason;
    if (lv.rejection == ViewRejection::kTooFewPatches) {
      std::ostringstream s;
      s << v.summary.patches_valid << " usable patches of "
        << v.summary.patches_tried;
      if (!v.summary.rejections.empty()) {
        s << " (" << CountsToString(v.summary.rejections) << ")";
      }
      s << "; need " << options_.linear.min_samples_per_view;
      out.reason = s.str();
    }
    out.focus_distance_model = lv.focus_model;
    out.single_view_scale = lv.single_solved ? lv.single_scale : kNaN;
    out.predicted_blur_range_px = lv.predicted_blur_range_px;
    out.median_abs_residual_px = lv.median_abs_residual_px;
    out.patches_tried = v.summary.patches_tried;
    out.patches_searched = v.summary.patches_searched;
    out.patches_valid = v.summary.patches_valid;
    out.patches_selected = selected_count[i];
    out.focus_distance_m = kNaN;
    for (const PatchSample& s : samples[i]) {
      PatchSample copy = s;
      copy.used = s.selected && lv.used;
      result.patches.push_back(copy);
    }
  }
  // Where the patches went, summed over views, for refusal messages
  // (refusal.h).
  std::vector<ViewPatchCounts> counts;
  for (const auto& v : views_) {
    counts.push_back({v->summary.patches_tried,
                      v->summary.patches_valid,
                      v->summary.rejections,
                      v->summary.max_radius_px});
  }
  const PatchAccount account = AccountPatches(counts);
  if (!linear.success) {
    result.failure_reason = account.leading_cause + linear.failure_reason +
                            account.Summary() + account.Fixes();
    return result;
  }
  // Intervals: the bootstrap's, widened by the systematic terms: the
  // estimator's own, and the thin lens's single plane against a real
  // lens's principal planes and entrance pupil (the origin of SfM depth),
  // which lie within about a focal length of each other: a relative depth
  // error of up to f / z at the patches' median distance.
  double lens_geometry = 0;
  if (options_.lens_geometry_uncertainty > 0) {
    std::vector<double> ratios;
    for (int i : linear.selected_views) {
      for (const PatchSample& p : samples[i]) {
        if (p.selected && p.depth > 0) {
          ratios.push_back(views_[i]->lens.focal_length_mm /
                           (ModelUnitMm(linear.scale) * p.depth));
        }
      }
    }
    if (!ratios.empty()) {
      lens_geometry =
          options_.lens_geometry_uncertainty * Percentile(ratios, 0.5);
    }
  }
  result.lens_geometry_uncertainty = lens_geometry;
  IntervalTerms terms;
  terms.systematic = options_.scale_systematic_uncertainty;
  terms.lens_geometry = lens_geometry;
  // The profile's own uncertainty (self-calibration): scale ~ the assumed
  // centroid offset, so the offsets the data allow move it by their ratio.
  if (options_.psf_self_calibration) {
    ProfileScaleFactors(field,
                        result,
                        &result.profile_scale_factor_low,
                        &result.profile_scale_factor_high);
    if (result.psf_self_calibrated) {
      // A fitted profile's shape: another kernel pair can satisfy the
      // cross-view identity as well as the family member that was fitted.
      const double u = options_.self_calibration_shape_uncertainty;
      result.profile_scale_factor_low *= 1 - u;
      result.profile_scale_factor_high *= 1 + u;
    }
  } else {
    result.profile_scale_factor_low = 1 - options_.profile_relative_uncertainty;
    result.profile_scale_factor_high =
        1 + options_.profile_relative_uncertainty;
  }
  terms.profile_low = result.profile_scale_factor_low;
  terms.profile_high = result.profile_scale_factor_high;
  const double statistical_width =
      (linear.scale_ci_high - linear.scale_ci_low) / linear.scale;
  terms.Widen(linear.scale, &linear.scale_ci_low, &linear.scale_ci_high);
  const double statistical_ci_low = linear.scale_ci_low;
  const double statistical_ci_high = linear.scale_ci_high;
  terms.ApplyProfile(&linear.scale_ci_low, &linear.scale_ci_high);
  // The recorded-focus cue (profile-free); used in the answer when
  // pin_to_recorded_focus allows it, reported as evidence either way.
  result.focus_cue = RecordedFocusCue(linear, lens_geometry);
  const bool use_focus =
      options_.pin_to_recorded_focus && result.focus_cue.valid;
  result.dp_cue = DPCue(linear);
  // What the linear stage found, kept in the result (and the report) even
  // when the interval check below refuses it.
  result.scale_initial = linear.scale;
  result.scale_initial_ci_low = linear.scale_ci_low;
  result.scale_initial_ci_high = linear.scale_ci_high;
  result.num_views_used = static_cast<int>(linear.selected_views.size());
  {
    const double width =
        (linear.scale_ci_high - linear.scale_ci_low) / linear.scale;
    std::ostringstream s;
    const bool no_interval = !std::isfinite(statistical_width);
    // The profile is what leaves the scale open: on its own, or on top of
    // an interval that would have been narrow enough.
    const double profile_width =
        result.profile_scale_factor_high - result.profile_scale_factor_low;
    const bool profile_open =
        !no_interval && !(width <= options_.max_scale_ci_relative_width) &&
        (!(profile_width <= options_.max_scale_ci_relative_width) ||
         (statistical_ci_high - statistical_ci_low) / linear.scale <=
             options_.max_scale_ci_relative_width);
    if (linear.num_rows < options_.min_total_patches || no_interval ||
        !(width <= options_.max_scale_ci_relative_width)) {
      s << account.leading_cause;
    }
    if (linear.num_rows < options_.min_total_patches) {
      s << "too few usable patches for a scale (" << linear.num_rows
        << " in the joint solve, need " << options_.min_total_patches << ")";
    } else if (no_interval) {
      s << "the scale's interval could not be measured ("
        << linear.interval_status << "): a scale without one is not reported";
    } else if (profile_open && !options_.psf_self_calibration) {
      s << CalibratedProfileOpenReason(options_.profile_relative_uncertainty,
                                       linear.scale,
                                       linear.scale_ci_low,
                                       linear.scale_ci_high,
                                       options_.max_scale_ci_relative_width,
                                       result.focus_cue.valid);
    } else if (profile_open) {
      s << UnknownProfileReason(
          result.psf_fit.reason +
              (result.psf_self_calibrated
                   ? "; a fitted profile's strength is uncertain by +-" +
                         std::to_string(std::lround(
                             100 *
                             options_.self_calibration_shape_uncertainty)) +
                         " % beyond the fit, for kernel shapes outside the "
                         "family that fit the patches as well"
                   : ""),
          linear.scale,
          linear.scale_ci_low,
          linear.scale_ci_high);
    } else if (!(width <= options_.max_scale_ci_relative_width)) {
      s << UndeterminedScaleReason(linear.scale,
                                   linear.scale_ci_low,
                                   linear.scale_ci_high,
                                   width,
                                   options_.max_scale_ci_relative_width);
    }
    if (!s.str().empty()) {
      // The DP data alone give no answer; with the recorded focus they may.
      if (use_focus && AdoptCombinedCues(linear, &result, &s)) {
        // Answered from the recorded focus (and the DP data if they agree).
      } else {
        if (options_.pin_to_recorded_focus && !result.focus_cue.valid) {
          s << RecordedFocusMissingHint(linear);
        }
        s << account.TypicalCauses() << account.Fixes();
        result.failure_reason = s.str();
        return result;
      }
    }
  }
  result.linear_median_abs_residual_px = linear.median_abs_residual_px;
  if (!result.scale_from_cues) {
    result.scale = linear.scale;
    result.scale_ci_low = linear.scale_ci_low;
    result.scale_ci_high = linear.scale_ci_high;
  }
  result.num_patches = linear.num_rows;

  // --- Intensity stage on the selected views and their stored patches. ---
  const auto start_intensity = std::chrono::steady_clock::now();
  IntensityStage(linear, samples, field, terms, &result);
  result.seconds_intensity = SecondsSince(start_intensity);
  if (!result.scale_from_cues) {
    // The DP data answered on their own; the recorded focus joins them.
    result.dp_cue.valid = true;
    result.dp_cue.scale = result.scale;
    result.dp_cue.ci_low = result.scale_ci_low;
    result.dp_cue.ci_high = result.scale_ci_high;
    if (use_focus) {
      std::ostringstream s;
      if (!AdoptCombinedCues(linear, &result, &s)) {
        result.failure_reason = s.str();
        return result;
      }
    } else {
      result.scale_source = "DP data";
      result.combination =
          result.focus_cue.valid
              ? "the DP data alone (the recorded focus is evidence only: "
                "pin_to_recorded_focus 0)"
              : "the DP data alone (no recorded focus)";
    }
  }

  // Focus distances and predicted blur under the final scale. g_i' is the
  // linear stage's (the intensity stage keeps it fixed), so the focus in
  // metres is s * g_i'.
  for (int i = 0; i < num_views; ++i) {
    DPViewResult& out = result.views[i];
    out.focus_distance_m = std::isfinite(out.focus_distance_model)
                               ? result.scale * out.focus_distance_model
                               : kNaN;
  }
  for (PatchSample& s : result.patches) {
    const DPViewResult& v = result.views[s.view];
    s.predicted_radius_px =
        std::isfinite(v.focus_distance_model)
            ? PredictBlurRadiusPx(v.lens,
                                  views_[s.view]->working_pitch_mm,
                                  result.scale,
                                  v.focus_distance_model,
                                  s.depth)
            : kNaN;
  }
  CheckAgainstRecordedFocus(&result);
  result.success = true;
  return result;
}

void DPScaleEstimator::IntensityStage(
    const LinearEstimate& linear,
    const std::vector<std::vector<PatchSample>>& samples,
    const DPPsfField& field,
    const IntervalTerms& terms,
    DPScaleResult* result) const {
  const std::shared_ptr<const DPPsfModel> psf = field.cells[0];
  const bool banded = field.cells.size() > 1;
  result->intensity_loss = IntensityLossName(options_.intensity.loss);
  if (result->scale_from_cues) {
    // The DP data alone left the scale open: the intensity stage reads the
    // same profile, the very thing that is uncertain here.
    result->intensity_status =
        "skipped: the DP data alone leave the scale open; it comes from "
        "the recorded focus";
  } else if (!options_.intensity_refinement) {
    result->intensity_status = "disabled; linear estimate kept";
  } else {
    std::vector<IntensityView> iviews;
    std::vector<IntensityPatch> ipatches;
    for (int i : linear.selected_views) {
      const ViewData& v = *views_[i];
      IntensityView iv;
      iv.lens = v.lens;
      iv.pixel_pitch_mm = v.working_pitch_mm;
      iv.focus_distance_model = linear.views[i].focus_model;
      const int index = static_cast<int>(iviews.size());
      iviews.push_back(iv);
      for (const StoredCrop& st : v.stored) {
        IntensityPatch ip;
        ip.view = index;
        if (!samples[i][st.sample].selected) continue;
        ip.depth = samples[i][st.sample].depth;
        if (banded) {
          ip.psf = field.cells[samples[i][st.sample].psf_band].get();
        }
        ip.left = st.left;
        ip.right = st.right;
        ip.border = st.border;
        ipatches.push_back(ip);
      }
    }
    IntensitySearchOptions search = options_.intensity;
    search.seed = options_.seed;
    search.num_threads = options_.num_threads;
    // Clamp radii to the blur search's bound of each view (the crops' border
    // supports exactly that).
    double max_r = 0;
    for (int i : linear.selected_views) {
      max_r = std::max(
          max_r,
          views_[i]->summary.max_radius_px *
              (result->psf_self_calibrated ? options_.psf_fit_radius_factor
                                           : 1.0));
    }
    search.max_radius_px = max_r;
    IntensitySearchResult intensity;
    try {
      intensity =
          SearchScaleByIntensity(iviews, ipatches, linear.scale, *psf, search);
    } catch (const std::exception& e) {
      intensity.success = false;
      intensity.failure_reason = e.what();
    }
    result->candidate_scales = intensity.candidate_scales;
    result->candidate_losses = intensity.candidate_losses;
    result->intensity_failed_evaluations = intensity.num_failed_evaluations;
    std::ostringstream status;
    if (!intensity.success) {
      status << "failed (" << intensity.failure_reason
             << "); linear estimate kept";
    } else {
      result->scale_intensity = intensity.scale;
      result->intensity_ci_low = intensity.scale_ci_low;
      result->intensity_ci_high = intensity.scale_ci_high;
      result->intensity_bootstrap_support = intensity.bootstrap_support;
      const double width =
          (intensity.scale_ci_high - intensity.scale_ci_low) / intensity.scale;
      if (intensity.at_boundary) {
        status << "loss minimum at the edge of the searched range (s* x (1 +- "
               << search.relative_range
               << ")): the linear and intensity cues disagree; linear "
                  "estimate kept";
      } else if (search.num_bootstrap == 0) {
        status << "no bootstrap (num_bootstrap 0), so no interval; linear "
                  "estimate kept";
      } else if (width > options_.max_intensity_ci_relative_width) {
        status << "loss curve too flat ("
               << std::lround(100 * search.confidence_level) << " % interval "
               << std::fixed << std::setprecision(1) << width * 100
               << " % of the scale); linear estimate kept";
      } else if (intensity.bootstrap_support <
                 options_.min_intensity_bootstrap_support) {
        status << "minimum not stable under resampling (support "
               << intensity.bootstrap_support << "); linear estimate kept";
      } else if (!IntervalContains(intensity.scale,
                                   intensity.scale_ci_low,
                                   intensity.scale_ci_high,
                                   options_.scale_systematic_uncertainty,
                                   linear.scale)) {
        // Both stages read the same patches; if they disagree beyond the
        // intensity stage's own interval (plus the systematic term), one of
        // them is wrong and the linear stage is the robust one (L1 over
        // per-patch estimates vs a sum of loss curves that a few patches can
        // pull).
        status << "disagrees with the linear estimate (intensity "
               << intensity.scale << ", interval [" << intensity.scale_ci_low
               << ", " << intensity.scale_ci_high << "] excludes the linear "
               << linear.scale << "); linear estimate kept";
      } else {
        status << "used (moved the scale by " << std::showpos << std::fixed
               << std::setprecision(2)
               << 100 * (intensity.scale / linear.scale - 1) << std::noshowpos
               << " % from the linear estimate)";
        result->intensity_used = true;
        result->scale = intensity.scale;
        result->scale_ci_low = intensity.scale_ci_low;
        result->scale_ci_high = intensity.scale_ci_high;
        terms.Widen(
            result->scale, &result->scale_ci_low, &result->scale_ci_high);
        terms.ApplyProfile(&result->scale_ci_low, &result->scale_ci_high);
        result->num_patches = intensity.num_patches;
      }
    }
    result->intensity_status = status.str();
  }
}

ScaleCue DPScaleEstimator::DPCue(const LinearEstimate& linear) const {
  ScaleCue cue;
  cue.scale = linear.scale;
  cue.ci_low = linear.scale_ci_low;
  cue.ci_high = linear.scale_ci_high;
  cue.valid = linear.num_rows >= options_.min_total_patches &&
              linear.scale > 0 && cue.ci_low > 0 &&
              std::isfinite(cue.ci_high) && cue.ci_high >= cue.ci_low;
  return cue;
}

ScaleCue DPScaleEstimator::RecordedFocusCue(const LinearEstimate& linear,
                                            double lens_geometry) const {
  ScaleCue cue;
  // The views that carry the cue: used, with a recorded focus and a fitted
  // focal plane g' (where the disparity changes sign, whatever the profile).
  std::vector<int> views;
  std::vector<double> object_m;
  std::vector<double> brackets;
  for (int i : linear.selected_views) {
    const DPLensData& lens = views_[i]->lens;
    if (!std::isfinite(lens.recorded_focus_mm) ||
        !(linear.views[i].focus_model > 0)) {
      continue;
    }
    try {
      object_m.push_back(
          FocusObjectDistanceMm(lens.recorded_focus_mm, lens.focal_length_mm) /
          1000);
      views.push_back(i);
      brackets.push_back(std::isfinite(lens.recorded_focus_bracket)
                             ? lens.recorded_focus_bracket
                             : 0.0);
    } catch (const std::invalid_argument&) {
      // Nearer than the lens can focus: no evidence.
    }
  }
  if (views.empty()) return cue;
  auto scale_of = [&](auto focus_model_of) {
    std::vector<double> scales;
    for (size_t k = 0; k < views.size(); ++k) {
      const double g = focus_model_of(views[k]);
      if (g > 0) scales.push_back(object_m[k] / g);
    }
    return scales.empty() ? kNaN : Percentile(scales, 0.5);
  };
  const double scale =
      scale_of([&](int i) { return linear.views[i].focus_model; });
  std::vector<double> resampled;
  const size_t num_resamples =
      linear.views[views[0]].focus_model_samples.size();
  for (size_t b = 0; b < num_resamples; ++b) {
    const double sb = scale_of([&](int i) {
      const auto& samples = linear.views[i].focus_model_samples;
      return b < samples.size() ? samples[b] : kNaN;
    });
    if (std::isfinite(sb)) resampled.push_back(sb);
  }
  if (resampled.size() < 10 || !(scale > 0)) return cue;
  const double alpha = 0.5 * (1.0 - options_.linear.confidence_level);
  double lo = std::min(scale, Percentile(resampled, alpha));
  double hi = std::max(scale, Percentile(resampled, 1 - alpha));
  // The record's own accuracy (the tolerance, and the window a camera
  // records as its focus: Canon's maker note gives a bracket, not a
  // distance), the estimator's systematic term and the lens geometry's, in
  // quadrature with the bootstrap's halves.
  const double bracket = Percentile(brackets, 0.5);
  const double sys =
      scale * std::sqrt(std::pow(options_.recorded_focus_tolerance, 2) +
                        bracket * bracket +
                        std::pow(options_.scale_systematic_uncertainty, 2) +
                        lens_geometry * lens_geometry);
  cue.scale = scale;
  cue.ci_low = scale - std::hypot(scale - lo, sys);
  cue.ci_high = scale + std::hypot(hi - scale, sys);
  cue.num_views = static_cast<int>(views.size());
  cue.valid = cue.ci_low > 0 && std::isfinite(cue.ci_high);
  return cue;
}

std::string DPScaleEstimator::RecordedFocusMissingHint(
    const LinearEstimate& linear) const {
  for (int i : linear.selected_views) {
    if (std::isfinite(views_[i]->lens.recorded_focus_mm)) return "";
  }
  return "; a recorded focus distance (lens.csv's focus_distance_m, or the "
         "camera's EXIF) would give the scale without the DP profile";
}

bool DPScaleEstimator::AdoptCombinedCues(const LinearEstimate& linear,
                                         DPScaleResult* result,
                                         std::ostringstream* refusal) const {
  const CombinedScale combined =
      CombineScaleCues(result->dp_cue, result->focus_cue);
  const double width = (combined.ci_high - combined.ci_low) / combined.scale;
  result->cue_agreement = combined.agreement;
  std::ostringstream s;
  s << std::setprecision(4);
  if (!(width <= options_.max_scale_ci_relative_width) ||
      !(combined.ci_low > 0)) {
    if (combined.agreement == CueAgreement::kDisagree) {
      *refusal << (refusal->str().empty() ? "" : "; ")
               << "the two cues to the scale disagree: "
               << DisagreementAdvice(result->dp_cue,
                                     result->focus_cue,
                                     width,
                                     options_.max_scale_ci_relative_width,
                                     !options_.psf_self_calibration);
    } else {
      *refusal << "; with the recorded focus of " << result->focus_cue.num_views
               << " view(s): " << combined.how << ", " << std::fixed
               << std::setprecision(1) << 100 * width
               << " % wide, also over the limit of "
               << 100 * options_.max_scale_ci_relative_width << " %";
    }
    return false;
  }
  result->scale_from_cues = true;
  result->scale_from_recorded_focus =
      combined.agreement == CueAgreement::kOneCue;
  result->pinned_profile_strength = result->focus_cue.scale / linear.scale;
  result->scale = combined.scale;
  result->scale_ci_low = combined.ci_low;
  result->scale_ci_high = combined.ci_high;
  result->scale_source = combined.source;
  result->combination = combined.how;
  s << "the scale comes from " << combined.source << ": " << combined.how
    << "; the recorded focus pins the profile's strength at "
    << std::setprecision(2) << result->pinned_profile_strength
    << " x the one used";
  result->psf_status += (result->psf_status.empty() ? "" : "; ") + s.str();
  return true;
}

void DPScaleEstimator::CheckAgainstRecordedFocus(DPScaleResult* result) const {
  // The fitted focal plane g' is where the disparity changes sign, whatever
  // the DP profile; a recorded focus distance (converted to the thin lens's
  // object distance) then gives the scale without any PSF.
  std::vector<double> scales;
  result->focus_scale = kNaN;
  for (size_t i = 0; i < result->views.size(); ++i) {
    DPViewResult& out = result->views[i];
    const DPLensData& lens = views_[i]->lens;
    out.focus_scale = kNaN;
    if (!out.used || !std::isfinite(lens.recorded_focus_mm) ||
        !(out.focus_distance_model > 0)) {
      continue;
    }
    try {
      out.focus_scale =
          FocusObjectDistanceMm(lens.recorded_focus_mm, lens.focal_length_mm) /
          1000 / out.focus_distance_model;
      scales.push_back(out.focus_scale);
    } catch (const std::invalid_argument&) {
      // A recorded focus nearer than the lens can focus: no evidence.
    }
  }
  if (scales.empty()) return;
  result->focus_scale = Percentile(scales, 0.5);
  result->focus_scale_ratio = result->dp_cue.scale / result->focus_scale;
  std::ostringstream s;
  s << std::setprecision(4) << "the recorded focus distances of "
    << scales.size() << " used view(s) give a scale of " << result->focus_scale;
  if (result->focus_cue.valid) {
    s << " in [" << result->focus_cue.ci_low << ", "
      << result->focus_cue.ci_high << "] (profile-free)";
  }
  if (result->dp_cue.valid) {
    s << "; the DP data alone give " << result->dp_cue.scale << " in ["
      << result->dp_cue.ci_low << ", " << result->dp_cue.ci_high << "], "
      << std::showpos << std::fixed << std::setprecision(1)
      << 100 * (result->focus_scale_ratio - 1) << std::noshowpos << " % off it";
    result->focus_agrees =
        result->focus_cue.valid &&
        CombineScaleCues(result->dp_cue, result->focus_cue).agreement ==
            CueAgreement::kAgree;
    if (result->focus_agrees) {
      s << ": they agree (core/scale/scale_cues.h)";
    } else {
      s << ": they DISAGREE (core/scale/scale_cues.h); a DP profile "
        << std::setprecision(2) << result->focus_scale_ratio
        << " x as strong as the one used would reconcile them";
    }
  } else {
    result->focus_agrees = true;
    s << "; the DP data alone leave the scale open";
  }
  if (!result->combination.empty()) {
    s << ". The answer: " << result->combination;
  }
  result->focus_check = s.str();
}

}  // namespace dpsfm
