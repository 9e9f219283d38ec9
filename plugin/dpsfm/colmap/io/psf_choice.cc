#include "dpsfm/colmap/io/psf_choice.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <memory>
#include <sstream>

#include "colmap/util/logging.h"
#include "dpsfm/colmap/io/lens_data.h"
#include "dpsfm/colmap/io/workspace.h"

namespace fs = std::filesystem;

namespace dpsfm {

void PsfChoice::ApplyTo(DPScaleOptions* core) const {
  core->self_calibration.mode = self_calibration;
  if (profile_relative_uncertainty > 0) {
    core->interval.profile_relative_uncertainty = profile_relative_uncertainty;
  }
  core->geometry.min_auto_radius_px =
      std::max(core->geometry.min_auto_radius_px, reference_radius_px);
  core->geometry.profile_covered_radius_px = covered_radius_px;
}

PsfChoice MakePsfField(const std::string& psf_model,
                       const std::string& psf_path) {
  PsfChoice choice;
  if (psf_model == "translating_disk" || psf_model == "auto") {
    if (!psf_path.empty()) {
      throw InputError(
          "--DPScaleEstimator.psf_path is only used with "
          "--DPScaleEstimator.psf_model calibrated (got " +
          psf_model + ")");
    }
    // An explicit translating disk is checked by the same fit, never
    // replaced (SelfCalibrationOptions::Mode::kCheck).
    choice.self_calibration = psf_model == "auto"
                                  ? SelfCalibrationOptions::Mode::kFit
                                  : SelfCalibrationOptions::Mode::kCheck;
    choice.field = DPPsfField::Uniform(std::make_shared<TranslatingDiskPsf>());
    return choice;
  }
  if (psf_model == "calibrated") {
    if (psf_path.empty()) {
      throw InputError(
          "--DPScaleEstimator.psf_model calibrated needs "
          "--DPScaleEstimator.psf_path (a profile written by colmap "
          "dp_psf_calibrator, or measured kernels)");
    }
    choice.self_calibration = SelfCalibrationOptions::Mode::kOff;
    const PsfProfileFile profile = ReadPsfProfile(psf_path);
    CheckProfileLight(profile, psf_path);
    choice.path = psf_path;
    choice.conditions = profile.conditions;
    choice.profile_relative_uncertainty = profile.uncertainty;
    // The blur the profile was measured at bounds the automatic search
    // from below (a profile calibrated at 10 px on a camera whose frames
    // the frame-size rule gives 3.5 px).
    if (profile.model == "measured_kernels") {
      choice.reference_radius_px = profile.reference_radius_px;
      // Beyond the blur the calibration's captures covered (older
      // profiles: the blur the kernels were measured at), they are
      // magnified copies (MeasuredKernelPsf): the estimate counts the
      // patches there and widens the interval for them.
      choice.covered_radius_px = profile.conditions.max_blur_px > 0
                                     ? profile.conditions.max_blur_px
                                     : profile.reference_radius_px;
    }
    choice.field = profile.MakeField(psf_path);
    return choice;
  }
  throw InputError("unknown --DPScaleEstimator.psf_model '" + psf_model +
                   "' (translating_disk, calibrated or auto)");
}

namespace {

std::string Short(double value) {
  std::ostringstream s;
  s << std::setprecision(4) << value;
  return s.str();
}

}  // namespace

std::vector<std::string> CheckViewsAgainstProfile(
    const PsfChoice& choice,
    const std::vector<ProfileCheckView>& views,
    bool profile_applies) {
  std::vector<std::string> warnings;
  if (choice.path.empty()) return warnings;  // no profile file
  const ProfileConditions& c = choice.conditions;
  const std::string name = fs::path(choice.path).filename().string();
  if (!c.Known()) {
    LOG(INFO) << "DP profile " << choice.path
              << " records no conditions (written before dp_psf_calibrator "
                 "recorded them): the views' f-number, focal length and "
                 "pitch are not checked against it";
    return warnings;
  }
  for (const ProfileCheckView& view : views) {
    const ResolvedLens& r = *view.lens;
    const std::string image = "image " + view.image_name + ": ";
    // A sixth of a stop: f/4 against f/4.5 (a third) is another aperture.
    if (c.f_number > 0 &&
        std::abs(std::log(r.lens.f_number / c.f_number)) > std::log(2.0) / 6) {
      const std::string line =
          image + "f/" + Short(r.lens.f_number) + " (" + r.f_number_source +
          ") but the DP profile " + name + " was measured at f/" +
          Short(c.f_number) +
          ": its strength holds for that aperture only; calibrate one at f/" +
          Short(r.lens.f_number) +
          " (colmap dp_psf_calibrator), correct "
          "the f-number, or pass --DPScaleEstimator.profile_applies 1 if "
          "the profile applies";
      if (!profile_applies) throw InputError(line);
      warnings.push_back(line + " (given: used as it is)");
    }
    if (c.focal_length_mm > 0 &&
        std::abs(r.lens.focal_length_mm / c.focal_length_mm - 1) > 0.05) {
      warnings.push_back(image + "focal length " +
                         Short(r.lens.focal_length_mm) + " mm (" +
                         r.focal_length_source + ") but the DP profile " +
                         name + " was measured at " + Short(c.focal_length_mm) +
                         " mm: its kernels may not hold at this focal length");
    }
    // The pitch at the profile's frame size: the same sensor gives the
    // same pitch whatever integer fraction of the camera the frames are.
    const int profile_long = std::max(c.frame_width, c.frame_height);
    if (c.pixel_pitch_um > 0 && profile_long > 0 &&
        view.camera_long_side_px > 0) {
      const double pitch_at_profile_frames =
          r.lens.pixel_pitch_um * view.camera_long_side_px / profile_long;
      if (std::abs(pitch_at_profile_frames / c.pixel_pitch_um - 1) > 0.1) {
        warnings.push_back(
            image + "pixel pitch " + Short(r.lens.pixel_pitch_um) + " um (" +
            r.pixel_pitch_source + ") over the camera's " +
            std::to_string(view.camera_long_side_px) + " px is " +
            Short(pitch_at_profile_frames) + " um at the " +
            std::to_string(profile_long) + " px frames the DP profile " + name +
            " was measured on, where its pitch was " + Short(c.pixel_pitch_um) +
            " um: another sensor (or frame crop) than the profile's");
      }
    }
  }
  for (const std::string& warning : warnings) LOG(WARNING) << warning;
  return warnings;
}

}  // namespace dpsfm
