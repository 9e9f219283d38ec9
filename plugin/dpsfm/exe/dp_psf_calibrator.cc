#include "dpsfm/exe/dp_psf_calibrator.h"

#include <cstdlib>
#include <iostream>

#include "dpsfm/colmap/controllers/calibration_controller.h"
#include "dpsfm/exe/command_boundary.h"
#include "dpsfm/exe/command_options.h"

namespace dpsfm {
namespace {

// The folder of the captures, the targets file and the profile to write.
void AddRequiredOptions(CommandOptions* manager,
                        CalibrationRunOptions* options) {
  manager->Group("Required");
  manager->AddRequired(
      "dp_image_path",
      &options->dp_image_path,
      "folder of the captures: left/<name> with right/<name> (or "
      "sum/<name>), or any layout when targets.csv has left and right "
      "columns (paths relative to this folder)");
  manager->AddRequired(
      "targets_path",
      &options->targets_path,
      "targets.csv: a header naming its columns (name, target_distance_m, "
      "focus_distance_m, focal_length_mm, f_number, pixel_pitch_um, and "
      "optionally left, right) and one row per capture; the pitch is of the "
      "DP frames' pixels in micrometres, distances in metres from the "
      "focal-plane mark");
  manager->AddRequired("output_path",
                       &options->output_path,
                       "profile file to write (.dpsf; its .npy kernel files "
                       "are written beside it and must stay there)");
}

// How the captures are read.
void AddCaptureOptions(CommandOptions* manager,
                       CalibrationRunOptions* options) {
  manager->Group("Captures");
  manager->AddDefault("DPPsfCalibrator.swap_dp_views",
                      &options->swap_dp_views,
                      "swap the left and right DP views");
  manager->AddDefault(
      "DPPsfCalibrator.dp_encoding",
      &options->dp_encoding,
      "how the DP frames encode light: auto (PNG/EXIF colour tags, else "
      "8-bit = srgb, 16-bit = linear), linear or srgb; the profile is "
      "measured in linear light either way");
  manager->AddDefault(
      "DPPsfCalibrator.entrance_pupil_mm",
      &options->entrance_pupil_mm,
      "where the lens's entrance pupil (the no-parallax point of panorama "
      "heads) lies in front of the focal-plane mark at the captures' focus, "
      "in mm; scene depths are measured from it (0: unknown, the thin "
      "lens's position)");
  manager->AddDefault("DPPsfCalibrator.measure_shape",
                      &options->measure_shape,
                      "measure the kernels' shape against stopped-down "
                      "captures of the same targets (f/16 or smaller)");
}

// The camera and lens the profile is filed under in the library.
void AddLibraryOptions(CommandOptions* manager,
                       CalibrationRunOptions* options) {
  manager->Group("The profile library");
  manager->AddDefault("DPPsfCalibrator.camera",
                      &options->camera,
                      "camera body the profile belongs to (EXIF Make / "
                      "Model, e.g. 'Canon / Canon EOS R6m2')");
  manager->AddDefault("DPPsfCalibrator.lens",
                      &options->lens,
                      "lens the profile belongs to (EXIF LensModel)");
}

// The fit's settings.
void AddFitOptions(CommandOptions* manager, CalibrationRunOptions* options) {
  manager->Group("Fit (rarely changed)");
  manager->AddDefault(
      "DPPsfCalibrator.transfer_uncertainty",
      &options->transfer_uncertainty,
      "how far a calibration on planes transfers to scenes, as a relative "
      "95 % uncertainty added to the fit's own (0.24: measured on real "
      "Canon R6 II scenes; 0 for simulated cameras)");
  manager->AddDefault("DPPsfCalibrator.patch_size",
                      &options->patch_size,
                      "patch side in pixels of the working frame (0: auto)");
  manager->AddDefault("DPPsfCalibrator.stride",
                      &options->stride,
                      "step between patches in pixels (0: auto)");
  manager->AddDefault("DPPsfCalibrator.max_radius_px",
                      &options->max_radius_px,
                      "largest blur radius searched, in pixels of the "
                      "working frame (0: auto, at least 10)");
  manager->AddDefault("DPPsfCalibrator.min_texture_snr",
                      &options->min_texture_snr,
                      "patches need this ratio of texture to sensor noise");
  manager->AddDefault("DPPsfCalibrator.max_patches_per_capture",
                      &options->max_patches_per_capture,
                      "patches used per capture (evenly spread)");
  manager->AddDefault("DPPsfCalibrator.grid_rows",
                      &options->grid_rows,
                      "rows of frame regions fitted on their own");
  manager->AddDefault("DPPsfCalibrator.grid_cols",
                      &options->grid_cols,
                      "columns of frame regions fitted on their own");
  manager->AddDefault("DPPsfCalibrator.num_bootstrap",
                      &options->num_bootstrap,
                      "bootstrap resamples for the intervals");
  manager->AddDefault("DPPsfCalibrator.num_threads",
                      &options->num_threads,
                      "threads (-1: all cores)");
}

// The command's options, in the groups --help shows.
void AddCommandOptions(CommandOptions* manager,
                       CalibrationRunOptions* options) {
  AddRequiredOptions(manager, options);
  AddCaptureOptions(manager, options);
  AddLibraryOptions(manager, options);
  AddFitOptions(manager, options);
}

}  // namespace

int RunDPPsfCalibrator(int argc, char** argv) {
  CalibrationRunOptions options;
  CommandOptions manager(
      "dp_psf_calibrator",
      "Measures a camera's dual-pixel (DP) blur profile from captures of a "
      "textured flat target at known distances (two or more, nearer and "
      "farther than the focus, several pixels of blur each) and writes it "
      "as a profile file for dp_scale_estimator --DPScaleEstimator."
      "psf_model calibrated. docs/psf-profiles.md explains the capture and "
      "the numbers it prints.",
      {"--dp_image_path captures --targets_path targets.csv --output_path "
       "camera.dpsf"});
  AddCommandOptions(&manager, &options);
  int exit_code = EXIT_SUCCESS;
  if (!manager.Parse(argc, argv, std::cout, &exit_code)) return exit_code;

  return RunAtCommandBoundary("dp_psf_calibrator",
                              [&] { return RunPsfCalibration(options); });
}

}  // namespace dpsfm
