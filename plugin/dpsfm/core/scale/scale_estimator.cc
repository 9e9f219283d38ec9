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
#include "dpsfm/core/scale/scale_estimator_data.h"
#include "dpsfm/core/scale/view_patches.h"
#include "dpsfm/core/scale/view_search.h"
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

}  // namespace

bool PatchGeometryOptions::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_GE(patch_size, 0);
  DPSFM_CHECK_OPTION_GE(stride, 0);
  DPSFM_CHECK_OPTION_GE(max_radius_px, 0);
  DPSFM_CHECK_OPTION_GE(min_auto_radius_px, 0);
  DPSFM_CHECK_OPTION_VALUE(search_bound_share > 0 && search_bound_share <= 1,
                           search_bound_share);
  DPSFM_CHECK_OPTION_GE(max_search_bound_growths, 0);
  DPSFM_CHECK_OPTION_GE(profile_covered_radius_px, 0);
  // 0 is automatic.
  DPSFM_CHECK_OPTION_VALUE(resize_factor >= 0 && resize_factor <= 1,
                           resize_factor);
  return true;
}

bool PatchSelectionOptions::Check(std::string* failure) const {
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
  return true;
}

bool IntensityStageOptions::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_GT(max_ci_relative_width, 0);
  DPSFM_CHECK_OPTION_VALUE(
      min_bootstrap_support >= 0 && min_bootstrap_support <= 1,
      min_bootstrap_support);
  DPSFM_CHECK_NESTED_OPTIONS(search);
  return true;
}

bool ScaleIntervalOptions::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_GT(max_scale_ci_relative_width, 0);
  DPSFM_CHECK_OPTION_GE(recorded_focus_tolerance, 0);
  DPSFM_CHECK_OPTION_GE(min_total_patches, 0);
  DPSFM_CHECK_OPTION_GE(scale_systematic_uncertainty, 0);
  DPSFM_CHECK_OPTION_GE(lens_geometry_uncertainty, 0);
  DPSFM_CHECK_OPTION_VALUE(
      profile_relative_uncertainty >= 0 && profile_relative_uncertainty < 1,
      profile_relative_uncertainty);
  return true;
}

bool SelfCalibrationOptions::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_VALUE(shape_uncertainty >= 0 && shape_uncertainty < 1,
                           shape_uncertainty);
  DPSFM_CHECK_OPTION_GE(max_patches, 1);
  DPSFM_CHECK_OPTION_VALUE(radius_factor >= 1 && radius_factor <= 4,
                           radius_factor);
  DPSFM_CHECK_OPTION_GE(bands, 1);
  DPSFM_CHECK_OPTION_GE(max_depth_spread, 0);
  if (mode != Mode::kOff) {
    DPSFM_CHECK_NESTED_OPTIONS(fit);
  }
  return true;
}

bool DPScaleOptions::Check(std::string* failure) const {
  DPSFM_CHECK_NESTED_OPTIONS(geometry);
  DPSFM_CHECK_NESTED_OPTIONS(patches);
  DPSFM_CHECK_NESTED_OPTIONS(interval);
  DPSFM_CHECK_OPTION_VALUE(num_threads == -1 || num_threads > 0, num_threads);
  DPSFM_CHECK_NESTED_OPTIONS(self_calibration);
  DPSFM_CHECK_NESTED_OPTIONS(blur);
  DPSFM_CHECK_NESTED_OPTIONS(linear);
  DPSFM_CHECK_NESTED_OPTIONS(intensity);
  return true;
}

DPScaleEstimator::DPScaleEstimator(const DPScaleOptions& options,
                                   std::shared_ptr<const DPPsfModel> psf)
    : DPScaleEstimator(options, DPPsfField::Uniform(std::move(psf))) {}

DPScaleEstimator::DPScaleEstimator(const DPScaleOptions& options,
                                   DPPsfField field)
    : options_(options), field_(std::move(field)) {
  DPSFM_CHECK_OPTIONS(options_, "DPScaleOptions");
  field_.CheckValid();
  DPSFM_CHECK(field_.cells.size() == 1 ||
              options_.self_calibration.mode ==
                  SelfCalibrationOptions::Mode::kOff)
      << "self-calibration fits one profile for the whole frame";
  psf_ = field_.cells[0];
  blur_estimators_.reset(
      new BlurSearchEstimators(field_, options_.num_threads));
}

DPScaleEstimator::~DPScaleEstimator() = default;

int DPScaleEstimator::NumViews() const {
  return static_cast<int>(views_.size());
}

DPViewSummary DPScaleEstimator::AddView(const DPView& view) {
  const auto start = std::chrono::steady_clock::now();
  CheckViewInput(view);
  std::unique_ptr<ViewData> data(new ViewData);
  DPViewSummary& summary = data->summary;
  summary.name = view.name;
  summary.frames = view.frames;
  summary.index = static_cast<int>(views_.size());
  summary.frame_size = FrameSize(view);
  data->lens = view.lens;

  const PatchGeometry geometry =
      ViewPatchGeometry(summary.frame_size, options_);
  const double rf = geometry.resize_factor;
  summary.resize_factor = rf;
  summary.initial_max_radius_px = geometry.max_radius_px;
  data->working_pitch_mm = view.lens.PixelPitchMm() / rf;
  const WorkingView working = MakeWorkingView(view, rf);
  summary.working_size = working.left.size();
  // 1 to 4: the usable patches, at a search bound that grows while the
  // view's blur lies beyond it.
  ViewSearch search(view,
                    working,
                    geometry,
                    field_,
                    options_,
                    blur_estimators_.get(),
                    summary.index);
  search.Run();
  search.Summarize(&summary);
  data->samples = search.TakeSamples();
  // 5. Top-T_c selection.
  const std::vector<int> top =
      SelectTopSamples(data->samples, search.Search(), options_);
  for (int i : top) data->samples[i].selected = true;
  summary.patches_kept = static_cast<int>(top.size());
  // 6. Crops of the best selected patches (crop_store.h), best first.
  data->stored = StoreBestCrops(working,
                                search.Candidates(),
                                data->samples,
                                top,
                                search.SampleCandidates(),
                                field_,
                                search.Geometry(),
                                search.Border(),
                                options_);

  summary.seconds = SecondsSince(start);
  views_.push_back(std::move(data));
  return summary;
}

cv::Mat DPScaleEstimator::ReduceFrame(const cv::Mat& frame) const {
  return ReduceFrame(frame, frame.size());
}

cv::Mat DPScaleEstimator::ReduceFrame(const cv::Mat& rows,
                                      const cv::Size& frame_size) const {
  if (rows.empty()) return rows;  // AddView refuses it, naming the view
  return WorkingFrame(rows,
                      ViewPatchGeometry(frame_size, options_).resize_factor);
}

int DPScaleEstimator::ReduceFrameStripRows(const cv::Size& frame_size) const {
  if (frame_size.empty()) return 0;
  return WorkingFrameStripRows(
      frame_size, ViewPatchGeometry(frame_size, options_).resize_factor);
}

bool DPScaleEstimator::LinearStage(
    const std::vector<std::vector<PatchSample>>& samples,
    LinearEstimate* linear,
    DPScaleResult* result) const {
  const auto start = std::chrono::steady_clock::now();
  const int num_views = static_cast<int>(views_.size());
  std::vector<LinearViewData> linear_views(num_views);
  for (int i = 0; i < num_views; ++i) {
    const ViewData& v = *views_[i];
    linear_views[i].name = v.summary.name;
    linear_views[i].lens = v.lens;
    linear_views[i].pixel_pitch_mm = v.working_pitch_mm;
    for (const PatchSample& s : samples[i]) {
      if (s.selected)
        linear_views[i].samples.push_back(
            {s.depth, s.radius_px, s.radius_se_px});
    }
  }
  LinearEstimatorOptions linear_options = options_.linear;
  linear_options.seed = options_.seed;
  linear_options.num_threads = options_.num_threads;
  try {
    *linear = EstimateScaleLinear(linear_views, linear_options);
  } catch (const CheckFailure& e) {
    result->refusal.code = ScaleRefusal::kLinearStageThrew;
    result->refusal.error = e.what();
    return false;
  }
  result->seconds.linear = SecondsSince(start);
  return true;
}

void DPScaleEstimator::AddViewResults(
    const LinearEstimate& linear,
    const std::vector<std::vector<PatchSample>>& samples,
    DPScaleResult* result) const {
  const int num_views = static_cast<int>(views_.size());
  result->views.resize(num_views);
  for (int i = 0; i < num_views; ++i) {
    const ViewData& v = *views_[i];
    const LinearViewResult& lv = linear.views[i];
    DPViewResult& out = result->views[i];
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
    out.patches_selected = 0;
    out.focus_distance_m = kNaN;
    for (const PatchSample& s : samples[i]) {
      out.patches_selected += s.selected;
      PatchSample copy = s;
      copy.used = s.selected && lv.used;
      result->patches.push_back(copy);
    }
  }
}

PatchAccount DPScaleEstimator::AccountForPatches() const {
  std::vector<ViewPatchCounts> counts;
  for (const auto& v : views_) {
    counts.push_back({v->summary.patches_tried,
                      v->summary.patches_valid,
                      v->summary.rejections,
                      v->summary.max_radius_px});
  }
  PatchAccount account = AccountPatches(counts);
  account.profile_covered_radius_px =
      options_.geometry.profile_covered_radius_px;
  return account;
}

double DPScaleEstimator::LensGeometryTerm(
    const LinearEstimate& linear,
    const std::vector<std::vector<PatchSample>>& samples) const {
  if (!(options_.interval.lens_geometry_uncertainty > 0)) return 0;
  std::vector<double> ratios;
  for (int i : linear.selected_views) {
    for (const PatchSample& p : samples[i]) {
      if (p.selected && p.depth > 0) {
        ratios.push_back(views_[i]->lens.focal_length_mm /
                         (ModelUnitMm(linear.scale) * p.depth));
      }
    }
  }
  if (ratios.empty()) return 0;
  return options_.interval.lens_geometry_uncertainty * Percentile(ratios, 0.5);
}

SearchBoundAccount DPScaleEstimator::AccountForSearchBound() const {
  SearchBoundAccount b;
  for (const auto& v : views_) {
    b.initial_max_radius_px =
        std::max(b.initial_max_radius_px, v->summary.initial_max_radius_px);
    b.max_radius_px = std::max(b.max_radius_px, v->summary.max_radius_px);
    b.views_grown += v->summary.search_bound_growths > 0;
    b.patches_searched += v->summary.patches_searched;
    b.patches_beyond_bound += v->summary.patches_beyond_bound;
    b.patches_undetermined += v->summary.patches_undetermined;
  }
  b.limits = b.patches_searched > 0 &&
             !(b.patches_beyond_bound <
               options_.geometry.search_bound_share * b.patches_searched);
  b.larger_radius_px = std::ceil(LargerSearchBound(b.max_radius_px));
  b.profile_covered_radius_px = options_.geometry.profile_covered_radius_px;
  return b;
}

void DPScaleEstimator::AccountForExtrapolation(
    const LinearEstimate& linear,
    const std::vector<std::vector<PatchSample>>& samples,
    SearchBoundAccount* bound) const {
  SearchBoundAccount& b = *bound;
  if (!(b.profile_covered_radius_px > 0) ||
      options_.self_calibration.mode != SelfCalibrationOptions::Mode::kOff) {
    return;
  }
  std::vector<double> beyond;  // ln(|r| / covered) of those beyond
  for (int i : linear.selected_views) {
    for (const PatchSample& p : samples[i]) {
      if (!p.selected) continue;
      ++b.samples;
      const double r = std::abs(p.radius_px);
      if (r > b.profile_covered_radius_px) {
        beyond.push_back(std::log(r / b.profile_covered_radius_px));
      }
    }
  }
  b.samples_beyond_coverage = static_cast<int>(beyond.size());
  if (beyond.empty()) return;
  b.extrapolation_uncertainty = options_.interval.profile_relative_uncertainty *
                                beyond.size() / b.samples *
                                Percentile(beyond, 0.5);
}

void DPScaleEstimator::SetProfileScaleFactors(const DPPsfField& field,
                                              DPScaleResult* result) const {
  if (options_.self_calibration.mode != SelfCalibrationOptions::Mode::kOff) {
    ProfileScaleFactors(field,
                        *result,
                        &result->psf.scale_factor_low,
                        &result->psf.scale_factor_high);
    if (result->psf.self_calibrated) {
      // A fitted profile's shape: another kernel pair can satisfy the
      // cross-view identity as well as the family member that was fitted.
      const double u = options_.self_calibration.shape_uncertainty;
      result->psf.scale_factor_low *= 1 - u;
      result->psf.scale_factor_high *= 1 + u;
    }
  } else {
    // A measured profile extended beyond the blur it covered
    // (AccountForSearchBound) is less certain there.
    const double u = std::hypot(options_.interval.profile_relative_uncertainty,
                                result->search_bound.extrapolation_uncertainty);
    result->psf.scale_factor_low = 1 - u;
    result->psf.scale_factor_high = 1 + u;
  }
}

OpenScale DPScaleEstimator::LinearRefusal(const LinearEstimate& linear,
                                          double statistical_width,
                                          double statistical_ci_low,
                                          double statistical_ci_high,
                                          const DPScaleResult& result) const {
  OpenScale open;
  open.num_rows = linear.num_rows;
  open.min_total_patches = options_.interval.min_total_patches;
  open.interval_status = linear.interval_status;
  open.scale = linear.scale;
  open.ci_low = linear.scale_ci_low;
  open.ci_high = linear.scale_ci_high;
  open.width = (linear.scale_ci_high - linear.scale_ci_low) / linear.scale;
  open.limit = options_.interval.max_scale_ci_relative_width;
  open.profile_relative_uncertainty =
      options_.interval.profile_relative_uncertainty;
  open.focus_recorded = result.cues.focus.valid;
  open.fit_reason = result.psf.fit.reason;
  open.self_calibrated = result.psf.self_calibrated;
  open.shape_uncertainty = options_.self_calibration.shape_uncertainty;
  const double width = open.width;
  const double limit = open.limit;
  const bool no_interval = !std::isfinite(statistical_width);
  // The profile is what leaves the scale open: on its own, or on top of an
  // interval that would have been narrow enough.
  const double profile_width =
      result.psf.scale_factor_high - result.psf.scale_factor_low;
  const bool profile_open =
      !no_interval && !(width <= limit) &&
      (!(profile_width <= limit) ||
       (statistical_ci_high - statistical_ci_low) / linear.scale <= limit);
  if (linear.num_rows < options_.interval.min_total_patches) {
    open.cause = OpenScaleCause::kTooFewPatches;
  } else if (no_interval) {
    open.cause = OpenScaleCause::kNoInterval;
  } else if (profile_open && options_.self_calibration.mode ==
                                 SelfCalibrationOptions::Mode::kOff) {
    open.cause = OpenScaleCause::kCalibratedProfile;
  } else if (profile_open) {
    open.cause = OpenScaleCause::kUnknownProfile;
  } else if (!(width <= limit)) {
    open.cause = OpenScaleCause::kWideInterval;
  }
  return open;
}

bool DPScaleEstimator::RecordedFocusJoins(const DPScaleResult& result) const {
  return options_.interval.pin_to_recorded_focus && result.cues.focus.valid;
}

bool DPScaleEstimator::JoinRecordedFocus(const LinearEstimate& linear,
                                         DPScaleResult* result) const {
  // The DP data answered on their own; the recorded focus joins them.
  result->cues.dp.valid = true;
  result->cues.dp.scale = result->scale;
  result->cues.dp.ci_low = result->scale_ci_low;
  result->cues.dp.ci_high = result->scale_ci_high;
  if (RecordedFocusJoins(*result)) {
    if (!AdoptCombinedCues(linear, result, &result->refusal.cues)) {
      result->refusal.code = ScaleRefusal::kCuesNotCombined;
      return false;
    }
    return true;
  }
  result->cues.source = "DP data";
  result->cues.dp_data_alone = true;
  return true;
}

void DPScaleEstimator::PredictUnderFinalScale(DPScaleResult* result) const {
  // g_i' is the linear stage's (the intensity stage keeps it fixed), so the
  // focus in metres is s * g_i'.
  for (DPViewResult& out : result->views) {
    out.focus_distance_m = std::isfinite(out.focus_distance_model)
                               ? result->scale * out.focus_distance_model
                               : kNaN;
  }
  for (PatchSample& s : result->patches) {
    const DPViewResult& v = result->views[s.view];
    s.predicted_radius_px =
        std::isfinite(v.focus_distance_model)
            ? PredictBlurRadiusPx(v.lens,
                                  views_[s.view]->working_pitch_mm,
                                  result->scale,
                                  v.focus_distance_model,
                                  s.depth)
            : kNaN;
  }
}

void DPScaleEstimator::SelfCalibrate(
    EstimateCaches* caches,
    std::vector<std::vector<PatchSample>>* samples,
    DPPsfField* field,
    DPScaleResult* result) const {
  if (options_.self_calibration.mode == SelfCalibrationOptions::Mode::kOff ||
      field_.cells.size() != 1) {
    return;
  }
  const auto fit_start = std::chrono::steady_clock::now();
  CalibrateProfile(
      samples, field, caches != nullptr ? &caches->profile : nullptr, result);
  result->psf.fit_ran = true;
  result->seconds.psf_fit = SecondsSince(fit_start);
}

void DPScaleEstimator::RefuseLinearFailure(const LinearEstimate& linear,
                                           const DPPsfField& field,
                                           const PatchAccount& account,
                                           DPScaleResult* result) const {
  result->refusal.code = ScaleRefusal::kLinearStageFailed;
  result->refusal.linear_failure = linear.failure;
  result->refusal.patches = account;
  if (result->psf.fit_ran) {
    // Whether the blur the views show is small, or only read small by a
    // profile the data leave open.
    SetProfileScaleFactors(field, result);
    const double low = result->psf.scale_factor_low;
    result->refusal.blur_read_factor =
        low > 0 ? 1 / low : std::numeric_limits<double>::infinity();
  }
}

DPScaleEstimator::IntervalTerms DPScaleEstimator::WidenLinearInterval(
    const std::vector<std::vector<PatchSample>>& samples,
    const DPPsfField& field,
    LinearEstimate* linear,
    StatisticalInterval* statistical,
    DPScaleResult* result) const {
  // The bootstrap's interval, widened by the systematic terms: the
  // estimator's own, and the thin lens's single plane against a real
  // lens's principal planes and entrance pupil (the origin of SfM depth),
  // which lie within about a focal length of each other: a relative depth
  // error of up to f / z at the patches' median distance. Then the
  // profile's own uncertainty (scale ~ the assumed centroid offset, so the
  // offsets the data allow move it by their ratio).
  const double lens_geometry = LensGeometryTerm(*linear, samples);
  result->lens_geometry_uncertainty = lens_geometry;
  AccountForExtrapolation(*linear, samples, &result->search_bound);
  SetProfileScaleFactors(field, result);
  IntervalTerms terms;
  terms.systematic = options_.interval.scale_systematic_uncertainty;
  terms.lens_geometry = lens_geometry;
  terms.profile_low = result->psf.scale_factor_low;
  terms.profile_high = result->psf.scale_factor_high;
  statistical->width =
      (linear->scale_ci_high - linear->scale_ci_low) / linear->scale;
  terms.Widen(linear->scale, &linear->scale_ci_low, &linear->scale_ci_high);
  statistical->ci_low = linear->scale_ci_low;
  statistical->ci_high = linear->scale_ci_high;
  terms.ApplyProfile(&linear->scale_ci_low, &linear->scale_ci_high);
  return terms;
}

bool DPScaleEstimator::AdoptLinearStage(const LinearEstimate& linear,
                                        const StatisticalInterval& statistical,
                                        const PatchAccount& account,
                                        DPScaleResult* result) const {
  // The recorded-focus cue (profile-free); used in the answer when
  // pin_to_recorded_focus allows it, reported as evidence either way.
  result->cues.focus =
      RecordedFocusCue(linear, result->lens_geometry_uncertainty);
  result->cues.dp = DPCue(linear);
  // What the linear stage found, kept in the result (and the report) even
  // when the interval check below refuses it.
  result->scale_initial = linear.scale;
  result->scale_initial_ci_low = linear.scale_ci_low;
  result->scale_initial_ci_high = linear.scale_ci_high;
  result->num_views_used = static_cast<int>(linear.selected_views.size());
  const OpenScale open = LinearRefusal(linear,
                                       statistical.width,
                                       statistical.ci_low,
                                       statistical.ci_high,
                                       *result);
  if (open.cause != OpenScaleCause::kNone) {
    // The DP data alone give no answer; with the recorded focus they may.
    CueRefusal cues;
    if (!(RecordedFocusJoins(*result) &&
          AdoptCombinedCues(linear, result, &cues))) {
      result->refusal.code = ScaleRefusal::kScaleOpen;
      result->refusal.open = open;
      result->refusal.cues = cues;
      result->refusal.recorded_focus_missing =
          options_.interval.pin_to_recorded_focus &&
          !result->cues.focus.valid && RecordedFocusMissing(linear);
      result->refusal.patches = account;
      return false;
    }
  }
  result->linear_median_abs_residual_px = linear.median_abs_residual_px;
  if (!result->cues.combined) {
    result->scale = linear.scale;
    result->scale_ci_low = linear.scale_ci_low;
    result->scale_ci_high = linear.scale_ci_high;
  }
  result->num_patches = linear.num_rows;
  return true;
}

DPScaleResult DPScaleEstimator::Estimate(EstimateCaches* caches) const {
  DPScaleResult result;
  for (const auto& v : views_) result.seconds.blur += v->summary.seconds;
  result.search_bound = AccountForSearchBound();
  if (views_.empty()) {
    result.refusal.code = ScaleRefusal::kNoViews;
    return result;
  }
  // The patches as the stages see them, and the PSF they use:
  // self-calibration may replace both.
  std::vector<std::vector<PatchSample>> samples;
  for (const auto& v : views_) samples.push_back(v->samples);
  DPPsfField field = field_;
  SelfCalibrate(caches, &samples, &field, &result);
  result.psf.model = field.Name();
  if (result.psf.rejected) {
    result.refusal.code = ScaleRefusal::kTranslatingDiskRejected;
    return result;
  }
  // --- Linear stage. ---
  LinearEstimate linear;
  if (!LinearStage(samples, &linear, &result)) return result;
  AddViewResults(linear, samples, &result);
  // Where the patches went, summed over views, for refusals (refusal.h).
  const PatchAccount account = AccountForPatches();
  if (!linear.success) {
    RefuseLinearFailure(linear, field, account, &result);
    return result;
  }
  StatisticalInterval statistical;
  const IntervalTerms terms =
      WidenLinearInterval(samples, field, &linear, &statistical, &result);
  if (!AdoptLinearStage(linear, statistical, account, &result)) return result;
  // --- Intensity stage on the selected views and their stored patches. ---
  const auto start_intensity = std::chrono::steady_clock::now();
  IntensityStage(linear,
                 samples,
                 field,
                 terms,
                 caches != nullptr ? &caches->intensity : nullptr,
                 &result);
  result.seconds.intensity = SecondsSince(start_intensity);
  if (!result.cues.combined && !JoinRecordedFocus(linear, &result)) {
    return result;
  }
  // Focus distances and predicted blur under the final scale.
  PredictUnderFinalScale(&result);
  CheckAgainstRecordedFocus(&result);
  result.success = true;
  return result;
}

}  // namespace dpsfm
