// The run of `colmap dp_psf_calibrator` (RunPsfCalibration): reading the
// targets and captures, the working frames and patches, the fit of the DP
// profile (core/calibration), the shape measurement, and the profile file.
// The command file only parses options, calls it and prints its one line.
#pragma once

#include <string>

#include "dpsfm/colmap/controllers/run_outcome.h"

namespace dpsfm {

// Paths and settings of one calibration, as given on the command line.
struct CalibrationRunOptions {
  std::string dp_image_path;
  std::string targets_path;
  std::string output_path;
  bool swap_dp_views = false;
  // auto, linear or srgb (colmap/io/dp_images.h, DecideEncoding).
  std::string dp_encoding = "auto";
  // How far a profile calibrated on planes transfers to scenes (relative,
  // 95 %), added in quadrature to the fit's own uncertainty in the
  // profile's `uncertainty`: a profile fits its planes to ~4 % but reads
  // real scenes up to 24 % off (the Canon R6 II scenes of ../shared/realdp:
  // the largest |ln r_s| of the seven, 0.236, with each view's own search
  // bound; leave-one-scene-out in docs/psf-profiles.md, "Transfer"). 0 for
  // a simulated camera whose scenes come from the same renderer.
  double transfer_uncertainty = 0.24;
  // Where the lens's entrance pupil lies in front of the focal-plane mark
  // at the captures' focus, in mm (0: unknown, the thin lens's position,
  // about f + f^2 / (g - f) from the sensor). Scene depths from SfM or a
  // registered depth camera are measured from the entrance pupil, so a
  // profile calibrated against distances from elsewhere reads them with
  // the difference: for the Canon RF 50 mm f/1.8 at ~1 m the pupil is
  // ~40 mm in front of the mark (the patent prescription, whole-group
  // focus), the thin lens puts it at ~52.5 mm, and the two planes' strength
  // moves by ~3 % (docs/psf-profiles.md, "Transfer").
  double entrance_pupil_mm = 0;
  // Patch geometry on the working frame; 0 = DefaultPatchGeometry.
  int patch_size = 0;
  int stride = 0;
  double max_radius_px = 0;
  double min_texture_snr = 1.5;
  int max_patches_per_capture = 150;
  // Regions of the frame fitted on their own (the profile changes across
  // the frame on real sensors; on the Canon R6 II mostly from the centre
  // to the left and right edges, and a 2 x 3 grid left a corner cell 25 %
  // uncertain from two planes).
  int grid_rows = 1;
  int grid_cols = 3;
  int num_bootstrap = 200;
  // For the profile library: the camera body (EXIF "Make / Model") and
  // lens (EXIF LensModel) the profile belongs to.
  std::string camera;
  std::string lens;
  // Measure the kernels' shape by deconvolution where a stopped-down
  // capture of the same target is given (else the family's shape at the
  // fitted strength is written).
  bool measure_shape = true;
  int num_threads = -1;

  // False at the first invalid option, which *failure (when given) names
  // with its value (core/util/check.h).
  bool Check(std::string* failure = nullptr) const;
};

// The whole calibration after option parsing. Throws InputError for what
// the user must fix; a failure outcome when the captures do not determine
// the profile.
RunOutcome RunPsfCalibration(const CalibrationRunOptions& options);

}  // namespace dpsfm
