// DP PSF profiles on disk, and the PSF a run uses.
//
// A profile file is plain text, one "key value" pair per line, '#' starts a
// comment (docs/user-guide.md, "DP PSF profiles"):
//
//   # dp-sfm DP PSF profile
//   format 1
//   model split_profile
//   split_exponent 0.62
//   crosstalk 0
//   rim_softness 0
//   band_split_exponents 0.45 0.62 0.80   (optional: the split exponent of
//                          each equal-width column band, left to right, for
//                          a profile that changes across the frame)
//   fit_<anything> ...    (how it was fitted; kept for people, ignored here)
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "dpsfm/core/dp_psf.h"
#include "dpsfm/core/dp_scale_estimator.h"

namespace dpsfm {

struct PsfProfileFile {
  SplitProfileParams params;
  // Empty = one profile for the whole frame.
  std::vector<double> band_split_exponents;
  // The fit_* lines, in file order.
  std::vector<std::pair<std::string, std::string>> fit_info;
};

// Throws InputError naming the file and line of what is wrong.
PsfProfileFile ReadPsfProfile(const std::string& path);
void WritePsfProfile(const std::string& path, const PsfProfileFile& profile);

// The PSF of --DPScaleEstimator.psf_model: "translating_disk" (the paper's
// model), "calibrated" (the profile in psf_path, from dp_psf_calibrator; one
// per column band if it has bands), or "auto" (the translating disk,
// self-calibrated from the data: sets core->psf_self_calibration). Throws
// InputError for an unknown model, a missing or malformed psf_path, or a
// psf_path the model does not use.
std::vector<std::shared_ptr<const DPPsfModel>> MakePsfModels(
    const std::string& psf_model,
    const std::string& psf_path,
    DPScaleOptions* core);

// One row of a calibration targets file (dp_psf_calibrator): a DP capture
// of a planar, fronto-parallel textured target.
struct CalibrationTarget {
  std::string name;              // DP view file name (as under left/)
  double target_distance_m = 0;  // sensor plane to target
  double focus_distance_m = 0;   // sensor plane to the focal plane
  DPLensData lens;               // pitch: of the DP frame's pixels
};

// CSV with the header
// name,target_distance_m,focus_distance_m,focal_length_mm,f_number,pixel_pitch_um
std::vector<CalibrationTarget> ReadCalibrationTargets(const std::string& path);

}  // namespace dpsfm
