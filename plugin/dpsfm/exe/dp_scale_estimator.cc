#include "dpsfm/exe/dp_scale_estimator.h"

#include <cstdlib>
#include <exception>
#include <iostream>

#include "colmap/controllers/option_manager.h"
#include "dpsfm/colmap/colmap_compat.h"
#include "dpsfm/colmap/scale_controller.h"
#include "dpsfm/colmap/workspace.h"
#include "dpsfm/core/dp_scale_estimator.h"

namespace dpsfm {
namespace {

// The one line a failed run leaves on stderr (besides earlier progress).
int Fail(const std::string& message) {
  std::cerr << "ERROR: dp_scale_estimator: " << message << std::endl;
  return EXIT_FAILURE;
}

void AddCommandOptions(colmap::OptionManager* manager,
                       DPScaleEstimatorOptions* options,
                       DPScaleOptions* core) {
  manager->AddDefaultOption("workspace_path",
                            &options->workspace_path,
                            "COLMAP dense workspace to rescale");
  manager->AddDefaultOption("input_path",
                            &options->input_path,
                            "sparse model to use instead of a dense workspace");
  manager->AddRequiredOption(
      "dp_image_path",
      &options->dp_image_path,
      "DP views: left/<name> with right/<name> or sum/<name>");
  manager->AddDefaultOption(
      "image_path", &options->image_path, "original images (EXIF lens data)");
  manager->AddDefaultOption(
      "database_path", &options->database_path, "project database, read only");
  manager->AddDefaultOption(
      "original_model_path",
      &options->original_model_path,
      "dense mode: the distorted model image_undistorter was run on (its "
      "cameras map depths into the DP frames' geometry)");
  manager->AddDefaultOption(
      "lens_path", &options->lens_path, "lens.csv with per-image lens data");
  manager->AddDefaultOption("input_type",
                            &options->input_type,
                            "{geometric, photometric} depth maps");
  manager->AddDefaultOption(
      "report_path", &options->report_path, "JSON report to write");
  manager->AddDefaultOption(
      "dry_run", &options->dry_run, "estimate and report, change nothing");
  manager->AddDefaultOption(
      "output_path",
      &options->output_path,
      "write a rescaled copy here instead of rescaling in place");
  manager->AddDefaultOption(
      "extra_model_paths",
      &options->extra_model_paths,
      "comma-separated sparse model folders in the same frame to rescale too");
  manager->AddDefaultOption(
      "force",
      &options->force,
      "rescale a workspace that was already rescaled (composes the scales)");
  manager->AddDefaultOption("DPScaleEstimator.focal_length_mm",
                            &options->focal_length_mm,
                            "focal length in mm for every image");
  manager->AddDefaultOption("DPScaleEstimator.f_number",
                            &options->f_number,
                            "f-number for every image");
  manager->AddDefaultOption("DPScaleEstimator.pixel_pitch_um",
                            &options->pixel_pitch_um,
                            "pixel pitch in um of the model camera's pixels");
  manager->AddDefaultOption(
      "DPScaleEstimator.swap_dp_views",
      &options->swap_dp_views,
      "swap left and right DP views (sensor with the opposite convention)");
  manager->AddDefaultOption(
      "DPScaleEstimator.dp_encoding",
      &options->dp_encoding,
      "how the DP frames encode light: auto (PNG/EXIF colour tags, else "
      "8-bit = srgb, 16-bit = linear), linear or srgb; frames are brought "
      "to linear light before the blur search");
  manager->AddDefaultOption(
      "DPScaleEstimator.psf_model",
      &options->psf_model,
      "DP PSF profile: translating_disk (the paper's), calibrated (the file "
      "in psf_path, from dp_psf_calibrator), auto (fitted to the data)");
  manager->AddDefaultOption("DPScaleEstimator.psf_path",
                            &options->psf_path,
                            "DP PSF profile file for psf_model calibrated");
  manager->AddDefaultOption(
      "DPScaleEstimator.psf_library",
      &options->psf_library,
      "folder of calibrated profiles (*.dpsf) picked by camera and lens "
      "with psf_model auto (default: $DPSFM_PROFILE_LIBRARY or "
      "~/.local/share/dp-sfm/profiles)");
  manager->AddDefaultOption(
      "DPScaleEstimator.max_views",
      &options->view_budget.max_views,
      "views visited at most (0: no cap); each keeps its best patches");
  manager->AddDefaultOption(
      "DPScaleEstimator.min_views",
      &options->view_budget.min_views,
      "views visited before the scale may be declared settled");
  manager->AddDefaultOption(
      "DPScaleEstimator.check_every",
      &options->view_budget.check_every,
      "views between two provisional estimates of the stopping rule");
  manager->AddDefaultOption("DPScaleEstimator.all_views",
                            &options->view_budget.all_views,
                            "visit every view (no stopping rule, no cap)");
  manager->AddDefaultOption(
      "DPScaleEstimator.prefetch_views",
      &options->prefetch_views,
      "views read ahead while the blur search runs (0: none)");
  // The method's parameters (paper names in brackets).
  manager->AddDefaultOption(
      "DPScaleEstimator.resize_factor",
      &core->resize_factor,
      "working resolution as a fraction of the DP frame (0: auto, about 10 "
      "px of search bound)");
  manager->AddDefaultOption("DPScaleEstimator.patch_size",
                            &core->patch_size,
                            "patch side in px of the working frame (0: auto)");
  manager->AddDefaultOption(
      "DPScaleEstimator.stride", &core->stride, "patch stride in px (0: auto)");
  manager->AddDefaultOption("DPScaleEstimator.max_radius_px",
                            &core->max_radius_px,
                            "blur radius search bound in px (0: auto)");
  manager->AddDefaultOption("DPScaleEstimator.top_patch_fraction",
                            &core->top_patch_fraction,
                            "[T_c] fraction of patches kept per view");
  manager->AddDefaultOption("DPScaleEstimator.blur_search_factor",
                            &core->blur_search_factor,
                            "blur search on the best this x T_c share of "
                            "patches (0: all, the paper's order)");
  manager->AddDefaultOption("DPScaleEstimator.min_blur_range_px",
                            &core->linear.min_blur_range_px,
                            "[T_p] views need a wider blur range (px)");
  manager->AddDefaultOption("DPScaleEstimator.num_selected_views",
                            &core->linear.num_selected_views,
                            "[N_v] views nearest the median kept");
  manager->AddDefaultOption("DPScaleEstimator.num_candidates",
                            &core->intensity.num_candidates,
                            "candidate scales of the intensity search");
  manager->AddDefaultOption("DPScaleEstimator.candidate_range",
                            &core->intensity.relative_range,
                            "[T_s] candidates span s* (1 +- this)");
  manager->AddDefaultOption("DPScaleEstimator.intensity_refinement",
                            &core->intensity_refinement,
                            "run the intensity-based search after the "
                            "linear estimate");
  manager->AddDefaultOption(
      "DPScaleEstimator.max_scale_ci_relative_width",
      &core->max_scale_ci_relative_width,
      "refuse when the scale's 95 % interval (data and DP profile) is "
      "wider than this fraction of it");
  manager->AddDefaultOption(
      "DPScaleEstimator.pin_to_recorded_focus",
      &core->pin_to_recorded_focus,
      "when the DP profile leaves the scale open, take it from the recorded "
      "focus distances (lens.csv focus_distance_m, EXIF) instead of refusing");
  manager->AddDefaultOption("DPScaleEstimator.recorded_focus_tolerance",
                            &core->recorded_focus_tolerance,
                            "relative accuracy of recorded focus distances");
  manager->AddDefaultOption("DPScaleEstimator.num_threads",
                            &core->num_threads,
                            "threads (-1: all cores)");
}

}  // namespace

int RunDPScaleEstimator(int argc, char** argv) {
  DPScaleEstimatorOptions options;
  DPScaleOptions core_options;

  colmap::OptionManager option_manager;
  AddCommandOptions(&option_manager, &options, &core_options);
  if (!ParseOptions(&option_manager, argc, argv)) return EXIT_FAILURE;
  options.num_threads = core_options.num_threads;

  try {
    const ScaleEstimationOutcome outcome =
        RunScaleEstimation(options, core_options);
    if (!outcome.success) return Fail(outcome.failure);
    return EXIT_SUCCESS;
  } catch (const InputError& error) {
    return Fail(error.what());
  } catch (const std::exception& error) {
    return Fail(std::string("internal error: ") + error.what());
  }
}

}  // namespace dpsfm
