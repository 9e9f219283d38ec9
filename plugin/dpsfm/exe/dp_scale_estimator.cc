#include "dpsfm/exe/dp_scale_estimator.h"

#include <cstdlib>
#include <iostream>

#include "dpsfm/colmap/controllers/scale_controller.h"
#include "dpsfm/colmap/io/workspace.h"
#include "dpsfm/core/scale/scale_estimator.h"
#include "dpsfm/exe/command_boundary.h"
#include "dpsfm/exe/command_options.h"

namespace dpsfm {
namespace {

void AddRequiredOptions(CommandOptions* manager, ScaleRunOptions* options) {
  manager->Group(
      "Required (and exactly one of --workspace_path, --input_path)");
  manager->AddRequired(
      "dp_image_path",
      &options->dp_image_path,
      "folder of the DP views: left/<image name> with right/<image name> "
      "(or sum/<image name>, the left + right frame)");
  manager->AddDefault("workspace_path",
                      &options->workspace_path,
                      "COLMAP dense workspace to rescale (sparse/ and "
                      "stereo/depth_maps/ from image_undistorter and "
                      "patch_match_stereo)");
  manager->AddDefault("input_path",
                      &options->input_path,
                      "sparse model to rescale instead (e.g. sparse/0; "
                      "depths from its triangulated points, no CUDA needed)");
}

void AddLensOptions(CommandOptions* manager, ScaleRunOptions* options) {
  manager->Group(
      "Lens data (per image: lens.csv, else the flags, else the images' "
      "metadata)");
  manager->AddDefault(
      "lens_path",
      &options->lens_path,
      "lens.csv: a header naming its columns (name, focal_length_mm, "
      "f_number, pixel_pitch_um, focus_distance_m, camera, lens) and one "
      "row per image with a cell for each column (empty cells allowed)");
  manager->AddDefault("image_path",
                      &options->image_path,
                      "original images, read for their metadata (EXIF and "
                      "maker notes; JPEG, TIFF, PNG, raw, CR3, HEIF): focal "
                      "length, f-number, pixel pitch, recorded focus, camera "
                      "and lens");
  manager->AddDefault("DPScaleEstimator.focal_length_mm",
                      &options->focal_length_mm,
                      "focal length in millimetres for every image (0: not "
                      "given)");
  manager->AddDefault("DPScaleEstimator.f_number",
                      &options->f_number,
                      "f-number for every image (0: not given)");
  manager->AddDefault(
      "DPScaleEstimator.pixel_pitch_um",
      &options->pixel_pitch_um,
      "pixel pitch in micrometres of the model camera's pixels (0: not "
      "given, then focal length in mm / focal length in px)");
  manager->AddDefault(
      "DPScaleEstimator.use_recorded_focus",
      &options->use_recorded_focus,
      "use the focus distance the camera recorded in the images' metadata "
      "(lens.csv's focus_distance_m is used either way)");
  manager->AddDefault(
      "DPScaleEstimator.lens_check_tolerance",
      &options->lens_check_tolerance,
      "how far each image's focal length / pixel pitch may differ from its "
      "camera's focal length in pixels, as a fraction beyond focus "
      "breathing, before the run stops");
}

void AddOutputOptions(CommandOptions* manager, ScaleRunOptions* options) {
  manager->Group("Output");
  manager->AddDefault("report_path",
                      &options->report_path,
                      "JSON report to write (plots are written beside it)");
  manager->AddDefault(
      "dry_run", &options->dry_run, "estimate and report, change nothing");
  manager->AddDefault(
      "output_path",
      &options->output_path,
      "write a rescaled copy into this folder instead of rescaling in place");
  manager->AddDefault("extra_model_paths",
                      &options->extra_model_paths,
                      "comma-separated sparse model folders in the same "
                      "frame to rescale too (e.g. sparse/0 of the project)");
  manager->AddDefault("force",
                      &options->force,
                      "rescale a workspace that was already rescaled (the "
                      "scales compose)");
}

void AddOtherInputOptions(CommandOptions* manager, ScaleRunOptions* options) {
  manager->Group("Other inputs");
  manager->AddDefault("database_path",
                      &options->database_path,
                      "the project database, read only (checks the model "
                      "against it; its cameras map depths into distorted "
                      "DP frames)");
  manager->AddDefault(
      "original_model_path",
      &options->original_model_path,
      "dense workspace: the distorted model image_undistorter was run on "
      "(its cameras map the depths into the DP frames' geometry)");
  manager->AddDefault("input_type",
                      &options->input_type,
                      "depth maps to read: geometric (falls back to "
                      "photometric) or photometric");
}

void AddDPProfileOptions(CommandOptions* manager, ScaleRunOptions* options) {
  manager->Group("DP frames and the DP profile");
  manager->AddDefault(
      "DPScaleEstimator.swap_dp_views",
      &options->swap_dp_views,
      "swap the left and right DP views (a sensor or export with the "
      "opposite convention; the refusal says when)");
  manager->AddDefault(
      "DPScaleEstimator.dp_encoding",
      &options->dp_encoding,
      "how the DP frames encode light: auto (PNG/EXIF colour tags, else "
      "8-bit = srgb, 16-bit = linear), linear or srgb; frames are brought "
      "to linear light before the blur search");
  manager->AddDefault(
      "DPScaleEstimator.psf_model",
      &options->psf_model,
      "the sensor's DP blur profile: auto (a library profile for the "
      "camera and lens, else fitted to the data), calibrated (the file in "
      "psf_path, from colmap dp_psf_calibrator) or translating_disk (the "
      "paper's, kept only where the data agree with it)");
  manager->AddDefault("DPScaleEstimator.psf_path",
                      &options->psf_path,
                      "DP profile file (.dpsf) for psf_model calibrated");
  manager->AddDefault(
      "DPScaleEstimator.psf_library",
      &options->psf_library,
      "folder of calibrated profiles (*.dpsf) picked by camera and lens "
      "with psf_model auto (empty: $DPSFM_PROFILE_LIBRARY or "
      "~/.local/share/dp-sfm/profiles)");
  manager->AddDefault(
      "DPScaleEstimator.profile_applies",
      &options->profile_applies,
      "use a calibrated profile for views whose f-number differs from the "
      "one it was measured at (its strength holds for its own aperture; "
      "without this such views are refused)");
}

void AddRefusalOptions(CommandOptions* manager, DPScaleOptions* core) {
  manager->Group("When a run refuses (the refusal names the one to change)");
  manager->AddDefault("DPScaleEstimator.max_radius_px",
                      &core->geometry.max_radius_px,
                      "largest blur radius searched, in pixels of the "
                      "working frame (0: about 10 px, from the frame size)");
  manager->AddDefault(
      "DPScaleEstimator.max_scale_ci_relative_width",
      &core->interval.max_scale_ci_relative_width,
      "refuse when the scale's 95 % interval (data and DP profile) is "
      "wider than this fraction of the scale");
  manager->AddDefault(
      "DPScaleEstimator.pin_to_recorded_focus",
      &core->interval.pin_to_recorded_focus,
      "when the DP profile leaves the scale open, take it from the recorded "
      "focus distances (lens.csv focus_distance_m, EXIF) instead of refusing");
  manager->AddDefault(
      "DPScaleEstimator.recorded_focus_tolerance",
      &core->interval.recorded_focus_tolerance,
      "relative accuracy of the recorded focus distances (0.1: within 10 %)");
}

void AddLargeProjectOptions(CommandOptions* manager,
                            ScaleRunOptions* options,
                            DPScaleOptions* core) {
  manager->Group("Large projects");
  manager->AddDefault(
      "DPScaleEstimator.max_views",
      &options->view_budget.max_views,
      "views visited at most (0: no cap); each keeps its best patches");
  manager->AddDefault("DPScaleEstimator.min_views",
                      &options->view_budget.min_views,
                      "views visited before the scale may be declared settled");
  manager->AddDefault(
      "DPScaleEstimator.check_every",
      &options->view_budget.check_every,
      "views between two provisional estimates of the stopping rule");
  manager->AddDefault("DPScaleEstimator.all_views",
                      &options->view_budget.all_views,
                      "visit every view (no stopping rule, no cap)");
  manager->AddDefault("DPScaleEstimator.prefetch_views",
                      &options->prefetch_views,
                      "views read ahead while the blur search runs (0: none)");
  manager->AddDefault("DPScaleEstimator.num_threads",
                      &core->num_threads,
                      "threads (-1: all cores)");
}

void AddMethodOptions(CommandOptions* manager, DPScaleOptions* core) {
  manager->Group("Method parameters (rarely changed; docs/user-guide.md)");
  manager->AddDefault(
      "DPScaleEstimator.resize_factor",
      &core->geometry.resize_factor,
      "working resolution as a fraction of the DP frame (0: automatic, "
      "about 10 px of blur search)");
  manager->AddDefault("DPScaleEstimator.patch_size",
                      &core->geometry.patch_size,
                      "patch side in pixels of the working frame (0: auto)");
  manager->AddDefault("DPScaleEstimator.stride",
                      &core->geometry.stride,
                      "step between patches in pixels of the working frame "
                      "(0: auto)");
  manager->AddDefault("DPScaleEstimator.top_patch_fraction",
                      &core->patches.top_patch_fraction,
                      "fraction of each view's patches kept, the most "
                      "confident first");
  manager->AddDefault("DPScaleEstimator.blur_search_factor",
                      &core->patches.blur_search_factor,
                      "run the blur search on the most textured patches, "
                      "this many times the kept fraction (0: on all)");
  manager->AddDefault("DPScaleEstimator.min_blur_range_px",
                      &core->linear.min_blur_range_px,
                      "a view is used only if its patches' blur spans more "
                      "than this many pixels");
  manager->AddDefault("DPScaleEstimator.num_selected_views",
                      &core->linear.num_selected_views,
                      "views kept for the joint solve: those whose own "
                      "scale is nearest the median");
  manager->AddDefault("DPScaleEstimator.num_candidates",
                      &core->intensity.search.num_candidates,
                      "candidate scales tried by the intensity search");
  manager->AddDefault("DPScaleEstimator.candidate_range",
                      &core->intensity.search.relative_range,
                      "the candidates span the linear estimate times 1 +- "
                      "this fraction");
  manager->AddDefault("DPScaleEstimator.intensity_refinement",
                      &core->intensity.enabled,
                      "refine the linear estimate by matching the DP views' "
                      "intensities");
}

// The command's options, in the groups --help shows.
void AddCommandOptions(CommandOptions* manager,
                       ScaleRunOptions* options,
                       DPScaleOptions* core) {
  AddRequiredOptions(manager, options);
  AddLensOptions(manager, options);
  AddOutputOptions(manager, options);
  AddOtherInputOptions(manager, options);
  AddDPProfileOptions(manager, options);
  AddRefusalOptions(manager, core);
  AddLargeProjectOptions(manager, options, core);
  AddMethodOptions(manager, core);
}

}  // namespace

int RunDPScaleEstimator(int argc, char** argv) {
  ScaleRunOptions options;
  DPScaleOptions core_options;

  CommandOptions command(
      "dp_scale_estimator",
      "Estimates the metric scale of a COLMAP reconstruction from its "
      "dual-pixel (DP) views and rescales the workspace in place (or into "
      "--output_path), so that it is in metres. Every view needs its focal "
      "length and f-number (lens.csv, the flags or EXIF). The run stops "
      "with one line naming the input and the fix when the data cannot "
      "give a trustworthy scale; docs/user-guide.md walks through a first "
      "run.",
      {"--workspace_path dense --dp_image_path dp --lens_path lens.csv",
       "--input_path sparse/0 --dp_image_path dp --image_path images "
       "--report_path report.json"});
  AddCommandOptions(&command, &options, &core_options);
  int exit_code = EXIT_SUCCESS;
  if (!command.Parse(argc, argv, std::cout, &exit_code)) return exit_code;

  return RunAtCommandBoundary("dp_scale_estimator", [&] {
    return RunScaleEstimation(options, core_options);
  });
}

}  // namespace dpsfm
