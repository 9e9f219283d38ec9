// DPScaleEstimator's self-calibration of the DP profile: the split profile
// fitted to the stored crops (core/calibration/psf_calibration.h), the
// crops searched again with it, and the factors the fit leaves open.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <utility>

#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/scale/refusal.h"
#include "dpsfm/core/scale/scale_estimator.h"
#include "dpsfm/core/scale/scale_estimator_data.h"
#include "dpsfm/core/util/check.h"
#include "dpsfm/core/util/threads.h"

namespace dpsfm {
namespace {

// A stored crop (16-bit) as the grey float patch the blur search takes.
cv::Mat GreyOfStoredCrop(const cv::Mat& crop) {
  cv::Mat f;
  crop.convertTo(f, CV_MAKETYPE(CV_32F, crop.channels()), 1.0 / 65535.0);
  return ToLuma(f);
}

std::shared_ptr<const DPPsfModel> ProfileOf(const SplitProfileFit& fit) {
  if (fit.translating_disk) return std::make_shared<TranslatingDiskPsf>();
  return std::make_shared<SplitProfilePsf>(fit.params);
}

// Widens [*low, *high] by the ratios of the centroid offsets the fit allows
// to `used`: the factors by which those profiles move the scale.
void WidenByConsistentOffsets(const SplitProfileFit& fit,
                              double used,
                              double* low,
                              double* high) {
  *low = std::min(*low, fit.consistent_low / used);
  *high = std::max(*high, fit.consistent_high / used);
}

// Scale factors the self-calibrated profile leaves open (see
// DPPsfResult::scale_factor_low): per cell of the field, the
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
    WidenByConsistentOffsets(fit, used, low, high);
  }
}

}  // namespace

DPScaleEstimator::StoredGroups DPScaleEstimator::GroupStoredCrops() const {
  StoredGroups groups;
  for (int i = 0; i < static_cast<int>(views_.size()); ++i) {
    const ViewData& v = *views_[i];
    for (int k = 0; k < static_cast<int>(v.stored.size()); ++k) {
      groups[{v.stored[k].left.cols, v.summary.max_radius_px}].push_back(
          {i, k});
    }
  }
  return groups;
}

std::vector<ProfilePatch> DPScaleEstimator::ProfileFitPatches(
    const std::vector<StoredRef>& group, int min_patches) const {
  // The flat ones (see SelfCalibrationOptions::max_depth_spread), evenly
  // over the views.
  std::vector<StoredRef> flat;
  std::vector<std::pair<double, size_t>> by_spread;
  for (size_t k = 0; k < group.size(); ++k) {
    const StoredRef& ref = group[k];
    const ViewData& v = *views_[ref.view];
    const double spread = v.samples[v.stored[ref.stored].sample].depth_spread;
    by_spread.emplace_back(spread, k);
    if (spread <= options_.self_calibration.max_depth_spread)
      flat.push_back(ref);
  }
  const size_t enough = 2 * static_cast<size_t>(min_patches);
  if (flat.size() < enough) {
    std::stable_sort(by_spread.begin(), by_spread.end());
    flat.clear();
    for (size_t i = 0; i < by_spread.size() && i < enough; ++i) {
      flat.push_back(group[by_spread[i].second]);
    }
    std::sort(
        flat.begin(), flat.end(), [](const StoredRef& a, const StoredRef& b) {
          return a.view != b.view ? a.view < b.view : a.stored < b.stored;
        });
  }
  const size_t step = std::max<size_t>(
      1,
      (flat.size() + options_.self_calibration.max_patches - 1) /
          options_.self_calibration.max_patches);
  std::vector<ProfilePatch> patches;
  for (size_t k = 0; k < flat.size(); k += step) {
    const StoredCrop& st = views_[flat[k].view]->stored[flat[k].stored];
    ProfilePatch patch;
    patch.left = GreyOfStoredCrop(st.left);
    patch.right = GreyOfStoredCrop(st.right);
    const ViewData& v = *views_[flat[k].view];
    patch.x_fraction =
        (v.samples[st.sample].x + 0.5) / v.summary.frame_size.width;
    patches.push_back(patch);
  }
  return patches;
}

int DPScaleEstimator::ReestimateStoredPatches(
    const StoredGroups& groups,
    const std::vector<std::shared_ptr<const DPPsfModel>>& fitted,
    std::vector<std::vector<PatchSample>>* samples,
    int* failures) const {
  int reestimated = 0;
  int failed = 0;
  for (const auto& g : groups) {
    BlurEstimationOptions blur = options_.blur;
    blur.max_radius_px =
        options_.self_calibration.radius_factor * g.first.second;
    std::vector<std::unique_ptr<PatchBlurEstimator>> estimators;
    for (const auto& band : fitted) {
      estimators.emplace_back(
          new PatchBlurEstimator(*band,
                                 blur,
                                 cv::Size(g.first.first, g.first.first),
                                 options_.num_threads));
    }
    const std::vector<StoredRef>& refs = g.second;
    // A crop the estimator cannot take (a failed DPSFM_CHECK) is counted
    // and left out; anything else thrown ends the run (ParallelFor).
    const int num_refs = static_cast<int>(refs.size());
    std::vector<char> redone(num_refs, 0), refused(num_refs, 0);
    ParallelFor(num_refs, options_.num_threads, [&](int k) {
      const ViewData& v = *views_[refs[k].view];
      const StoredCrop& st = v.stored[refs[k].stored];
      PatchSample& s = (*samples)[refs[k].view][st.sample];
      try {
        const PatchBlurEstimate e = estimators[s.psf_band]->Estimate(
            GreyOfStoredCrop(st.left), GreyOfStoredCrop(st.right));
        if (e.valid && !e.at_bound && std::isfinite(e.radius_px)) {
          s.radius_px = e.radius_px;
          s.radius_se_px = e.radius_se_px;
          s.radius_frame_px = e.radius_px / v.summary.resize_factor;
          s.fit_quality = e.fit_quality;
          s.selected = true;
          redone[k] = 1;
        }
      } catch (const CheckFailure&) {
        refused[k] = 1;
      }
    });
    reestimated +=
        static_cast<int>(std::count(redone.begin(), redone.end(), 1));
    failed += static_cast<int>(std::count(refused.begin(), refused.end(), 1));
  }
  *failures = failed;
  return reestimated;
}

void DPScaleEstimator::CalibrateProfile(
    std::vector<std::vector<PatchSample>>* samples,
    DPPsfField* field,
    ProfileSearchCache* cache,
    DPScaleResult* result) const {
  // FitSplitProfile takes one geometry (crop size, radius bound); the
  // largest group of stored crops feeds it.
  const StoredGroups groups = GroupStoredCrops();
  const std::vector<StoredRef>* largest = nullptr;
  double bound = 0;
  for (const auto& g : groups) {
    if (largest == nullptr || g.second.size() > largest->size()) {
      largest = &g.second;
      bound = g.first.second;
    }
  }
  if (largest == nullptr) {
    result->psf.status =
        "self-calibration could not determine the DP profile (no stored "
        "patch to fit it to: no view had usable texture and depth); " +
        psf_->Name() + " kept";
    return;
  }
  SplitProfileFitOptions fit_options = options_.self_calibration.fit;
  fit_options.blur = options_.blur;
  fit_options.blur.max_radius_px =
      options_.self_calibration.radius_factor * bound;
  fit_options.num_threads = options_.num_threads;
  fit_options.seed = options_.seed;
  const std::vector<ProfilePatch> patches =
      ProfileFitPatches(*largest, fit_options.min_patches);
  SplitProfileCalibration calibration;
  try {
    calibration = CalibrateSplitProfile(patches,
                                        options_.self_calibration.bands,
                                        fit_options,
                                        0.02,
                                        /*bands_when_frame_fits=*/false,
                                        cache);
  } catch (const CheckFailure& e) {
    calibration.summary = e.what();  // said in the status below
  }
  result->psf.fit = calibration.frame;
  result->psf.fit_searches_reused = calibration.searches_reused;
  result->psf.fit_searches_run = calibration.searches_run;
  if (options_.self_calibration.mode == SelfCalibrationOptions::Mode::kCheck) {
    CheckTranslatingDisk(calibration, result);
    return;
  }
  const SplitProfileFit& fit = calibration.frame;
  std::ostringstream status;
  // The profiles to use: one for the whole frame, or one per band (a band
  // may keep the translating disk).
  std::vector<std::shared_ptr<const DPPsfModel>> fitted;
  if (calibration.banded) {
    result->psf.band_fits = calibration.bands;
    for (const SplitProfileFit& band : calibration.bands) {
      fitted.push_back(ProfileOf(band));
    }
  } else if (!fit.determined) {
    status << "self-calibration could not determine the DP profile ("
           << calibration.summary << "); " << psf_->Name() << " kept";
    result->psf.status = status.str();
    return;
  } else if (fit.translating_disk) {
    status << "self-calibration kept the translating disk (" << fit.reason
           << ")";
    result->psf.status = status.str();
    return;
  } else {
    fitted.push_back(ProfileOf(fit));
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
  int failures = 0;
  const int reestimated =
      ReestimateStoredPatches(groups, fitted, samples, &failures);
  status << "self-calibrated DP profile: "
         << (calibration.banded ? calibration.summary : fit.reason) << "; "
         << reestimated << " stored patches re-estimated with it";
  if (failures > 0) {
    status << " (" << failures << " could not be searched and were left out)";
  }
  result->psf.status = status.str();
  result->psf.self_calibrated = true;
  *field = fitted_field;
}

void DPScaleEstimator::CheckTranslatingDisk(
    const SplitProfileCalibration& calibration, DPScaleResult* result) const {
  const SplitProfileFit& fit = calibration.frame;
  if (!calibration.banded && !fit.determined) {
    // The scale carries the offsets the data allow (ProfileScaleFactors).
    result->psf.status =
        "self-calibration could not check the translating "
        "disk (" +
        calibration.summary + ")";
    return;
  }
  if (!calibration.banded && fit.translating_disk) {
    result->psf.status =
        "the data agree with the translating disk (" + fit.reason + ")";
    return;
  }
  // The data determine another profile (for the frame, or for a band): the
  // scale under the disk would be off by the ratio of the offsets they
  // allow to the disk's.
  std::vector<SplitProfileFit> fits = calibration.banded
                                          ? calibration.bands
                                          : std::vector<SplitProfileFit>{fit};
  double low = std::numeric_limits<double>::infinity(), high = 0;
  for (const SplitProfileFit& f : fits) {
    if (f.translating_disk || !(f.translating_disk_centroid_offset > 0)) {
      continue;
    }
    WidenByConsistentOffsets(
        f, f.translating_disk_centroid_offset, &low, &high);
  }
  result->psf.rejected = true;
  result->refusal.disk.fit_summary =
      calibration.banded ? calibration.summary : fit.reason;
  result->refusal.disk.factor_low = low;
  result->refusal.disk.factor_high = high;
}

void DPScaleEstimator::ProfileScaleFactors(const DPPsfField& field,
                                           const DPScaleResult& result,
                                           double* low,
                                           double* high) const {
  if (!result.psf.band_fits.empty() && field.cells.size() > 1) {
    ProfileScaleFactorsOf(result.psf.band_fits, true, low, high);
  } else {
    ProfileScaleFactorsOf(
        {result.psf.fit}, result.psf.self_calibrated, low, high);
  }
}

}  // namespace dpsfm
