// DP PSF profiles on disk: the profile file format, read and written.
//
// A profile file is plain text, one "key value" pair per line, '#' starts a
// comment (docs/user-guide.md, "DP PSF profiles"). Three models:
//
//   format 1
//   model split_profile
//   split_exponent 0.62
//   crosstalk 0
//   rim_softness 0
//   rim_brightness 0      (optional: light weighted by 1 + b (rho / R)^2)
//   band_split_exponents 0.45 0.62 0.80   (optional: the split exponent of
//                          each equal-width column band, left to right, for
//                          a profile that changes across the frame)
//
//   format 1
//   model measured_kernels
//   reference_radius_px 11.5      the |r| at which the kernels were measured
//   side far                      far or near: the side of focus they are for
//   grid 6 8                      rows cols, row-major (default 1 1)
//   region 0.1667 0.1667 0.8333 0.8333   x0 y0 x1 y1 of the grid, fractions
//                                 of the frame (default 0 0 1 1)
//   left kernels_left.npy         float32/float64 (rows*cols, K, K),
//                                 (rows, cols, K, K) or
//   right kernels_right.npy       (K, K) for one cell; relative to the file
//
//   format 1
//   model translating_disk        the paper's model, stated for a camera
//   uncertainty 0.05              (its author's word; trusted like any
//                                 profile file, unlike psf_model
//                                 translating_disk, which is checked)
//
// (docs/user-guide.md, "Profile files": published calibrations import as
// they are). All may carry
//   camera <EXIF Make> / <EXIF Model>   lens <EXIF LensModel>
// for the profile library, uncertainty <relative 95 % of the strength>,
// light <linear|srgb> (what the kernels were measured in), and
// fit_<anything> lines (how it was made; kept for people, ignored by the
// estimator), and the conditions it was measured under (ProfileConditions:
//   focal_length_mm 49.57   f_number 4   pixel_pitch_um 46.875
//   frame_size 512 768      blur_range_px 2.95 4.93
// checked against each view's lens data before an estimate).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/core/optics/dp_psf.h"

namespace dpsfm {

// The conditions a calibrated profile was measured under, as
// dp_psf_calibrator writes them (0 = not recorded: profiles written before,
// hand-written or imported ones).
struct ProfileConditions {
  double focal_length_mm = 0;
  double f_number = 0;
  double pixel_pitch_um = 0;              // of the calibration's DP frames
  int frame_width = 0, frame_height = 0;  // the DP frames', px
  // The |blur radius| of the captures whose blur measured the strength, in
  // px of the DP frames.
  double min_blur_px = 0, max_blur_px = 0;
  bool Known() const {
    return focal_length_mm > 0 || f_number > 0 || pixel_pitch_um > 0;
  }
};

struct PsfProfileFile {
  // or "measured_kernels", "translating_disk"
  std::string model = "split_profile";
  // split_profile.
  SplitProfileParams params;
  // Empty = one profile for the whole frame.
  std::vector<double> band_split_exponents;
  // measured_kernels: one CV_32FC1 pair per layout cell (row-major).
  double reference_radius_px = 0;
  bool far_side = true;
  DPPsfLayout layout;
  std::vector<cv::Mat> left_kernels, right_kernels;
  // For the profile library (may be empty).
  std::string camera, lens;
  // Relative 95 % uncertainty of the profile's strength (the calibration's
  // interval): the scale inherits it (ScaleIntervalOptions::
  // profile_relative_uncertainty). 0 = not given.
  double uncertainty = 0;
  // The light the profile was measured in: "linear" (dp_psf_calibrator
  // brings frames to linear light, as the estimator does), "srgb" (measured
  // on sRGB-encoded values), or "" when the file does not say (hand-written
  // or imported kernels; profiles written before frames were linearised
  // carry fit_ lines but no `light`, and are refused).
  std::string light;
  // The fit_* lines, in file order.
  std::vector<std::pair<std::string, std::string>> fit_info;
  ProfileConditions conditions;

  // The PSF of every stage. Throws InputError (naming `path`) for kernels
  // that are no PSF pair under the DP conventions.
  DPPsfField MakeField(const std::string& path) const;
};

// Throws InputError naming the file and line of what is wrong.
PsfProfileFile ReadPsfProfile(const std::string& path);
// measured_kernels writes <stem>_left.npy and <stem>_right.npy beside it.
void WritePsfProfile(const std::string& path, const PsfProfileFile& profile);

// Throws InputError (naming `path` and the fix) for a profile measured in
// other than linear light: `light srgb`, or a calibrator's profile that
// records no light (written before frames were linearised).
void CheckProfileLight(const PsfProfileFile& profile, const std::string& path);

}  // namespace dpsfm
