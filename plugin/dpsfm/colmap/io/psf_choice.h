// The PSF a run uses (--DPScaleEstimator.psf_model / psf_path), and each
// view's lens data checked against the conditions its profile was measured
// under.
#pragma once

#include <string>
#include <vector>

#include "dpsfm/colmap/io/psf_profile.h"
#include "dpsfm/core/optics/dp_psf.h"
#include "dpsfm/core/scale/scale_estimator.h"

namespace dpsfm {

struct ResolvedLens;

// What a --DPScaleEstimator.psf_model / psf_path choice found: the PSF
// and what it means for the estimate's options. The controller applies it
// (ApplyTo) before DPScaleOptions::Check().
struct PsfChoice {
  DPPsfField field;
  // translating_disk: checked against the data (kCheck); auto: the
  // translating disk self-calibrated from the data (kFit); calibrated: kOff.
  SelfCalibrationOptions::Mode self_calibration =
      SelfCalibrationOptions::Mode::kFit;
  // A profile file's own relative uncertainty (0: none given).
  double profile_relative_uncertainty = 0;
  // The blur a measured-kernel profile was measured at: it bounds the
  // automatic search radius from below (0: no bound).
  double reference_radius_px = 0;
  // The largest blur a measured-kernel profile's calibration covered:
  // beyond it the kernels are magnified copies (0: a model profile).
  double covered_radius_px = 0;

  // A profile file's path and the conditions it records (calibrated).
  std::string path;
  ProfileConditions conditions;

  // The choice written into the estimate's options.
  void ApplyTo(DPScaleOptions* core) const;
};

// One view as CheckViewsAgainstProfile sees it.
struct ProfileCheckView {
  std::string image_name;
  const ResolvedLens* lens = nullptr;  // pitch of the model camera's pixels
  int camera_long_side_px = 0;         // the model camera's
};

// Each view's lens data against the conditions a calibrated profile was
// measured under, before the estimate. An f-number other than the
// profile's (by more than a sixth of a stop) throws InputError in one line
// naming the image, its f-number and source, the profile's and
// --DPScaleEstimator.profile_applies, unless `profile_applies`; another
// focal length (5 %) or another sensor (the pitch at the profile's frame
// size, 10 %) is a warning line (logged, and returned). A profile that
// records no conditions is said so once in the log, and nothing checked.
std::vector<std::string> CheckViewsAgainstProfile(
    const PsfChoice& choice,
    const std::vector<ProfileCheckView>& views,
    bool profile_applies);

// The PSF of --DPScaleEstimator.psf_model: "translating_disk" (the paper's
// model, checked against the data), "calibrated" (the profile in psf_path: a
// split profile from dp_psf_calibrator, one per column band if it has bands,
// or measured kernels), or "auto" (the translating disk, self-calibrated from
// the data). Throws InputError for an unknown model, a missing or malformed
// psf_path, or a psf_path the model does not use.
PsfChoice MakePsfField(const std::string& psf_model,
                       const std::string& psf_path);

}  // namespace dpsfm
