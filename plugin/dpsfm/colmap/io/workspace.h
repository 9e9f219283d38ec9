// What `colmap dp_scale_estimator` reads: the command's paths and settings,
// checked against what is on disk before anything is read or written.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "dpsfm/colmap/util/input_error.h"
#include "dpsfm/core/scale/view_budget.h"

namespace dpsfm {

// Paths and settings of one run, as given on the command line
// (docs/user-guide.md, "Options"). Empty strings and zero values mean "not
// given".
struct ScaleRunOptions {
  // COLMAP dense workspace (sparse/, stereo/depth_maps/, fused.ply, ...).
  std::string workspace_path;
  // A sparse model directory, used instead of workspace_path (depths from
  // the model's triangulated points).
  std::string input_path;
  // DP views: <dp_image_path>/left/<name> with right/<name> or sum/<name>.
  std::string dp_image_path;
  // Original images, read for their metadata (colmap/io/image_metadata.h):
  // focal length, f-number, pixel pitch, recorded focus, camera and lens.
  std::string image_path;
  // The project database; opened read-only, never created.
  std::string database_path;
  // Dense mode: the (distorted) model image_undistorter was run on, e.g.
  // sparse/0. Its refined cameras map the undistorted depth maps into the DP
  // frames' original geometry; they take precedence over the database's
  // cameras (which hold feature extraction's initial guesses).
  std::string original_model_path;
  // Per-image lens data (name,focal_length_mm,f_number,pixel_pitch_um).
  std::string lens_path;
  // Which depth maps to read: "geometric" (falls back to photometric) or
  // "photometric".
  std::string input_type = "geometric";
  std::string report_path;
  // Write a rescaled copy here instead of rescaling in place.
  std::string output_path;
  // Comma-separated sparse model folders in the same frame, rescaled along
  // with the workspace.
  std::string extra_model_paths;
  bool dry_run = false;
  // Consent to rescale a workspace that was already rescaled.
  bool force = false;

  // Lens flags; 0 means "not given" (lens.csv and the images' metadata may
  // supply them).
  double focal_length_mm = 0.0;
  double f_number = 0.0;
  double pixel_pitch_um = 0.0;
  // Use the focus distance the camera recorded in the images' metadata
  // (lens.csv's focus_distance_m is used either way).
  bool use_recorded_focus = true;
  // Relative tolerance of each image's f_mm / pitch against its camera's
  // f_px, beyond focus breathing (lens_data.h, CheckLensAgainstCamera).
  double lens_check_tolerance = 0.1;
  bool swap_dp_views = false;
  // How the DP frames encode light: "auto" (colmap/io/dp_images.h,
  // DecideEncoding), "linear" or "srgb". Frames are brought to linear
  // light before the blur search either way.
  std::string dp_encoding = "auto";
  // The DP PSF profile: translating_disk, calibrated (psf_path) or auto
  // (self-calibrated from the data; the default since the profile benchmark
  // showed it equal to translating_disk on translating-disk data and far
  // better on every other profile, docs/psf-profiles.md); see
  // psf_choice.h.
  std::string psf_model = "auto";
  std::string psf_path;
  // The DP profile library (psf_library.h, FindLibraryProfile); "" = the
  // default folder. With psf_model auto, a library profile whose camera and
  // lens match every view's is used as calibrated.
  std::string psf_library;
  // Use a calibrated profile for views whose f-number differs from the
  // one it was measured at (ProfileConditions; refused otherwise).
  bool profile_applies = false;
  // Which views to visit and when to stop (large projects).
  ViewBudgetOptions view_budget;
  // Views read ahead of the blur search on as many worker threads (0: read
  // each when it is needed; the controller reads in place too when the
  // estimate runs on one thread). Each one
  // waiting costs a view's frames and depth map in memory.
  int prefetch_views = 1;

  // False at the first invalid option, which *failure (when given) names in
  // the words of the command line (core/util/check.h). Values only: what
  // is on disk is checked by ResolveWorkspaceLayout and the rescale plan.
  bool Check(std::string* failure = nullptr) const;
};

// Where each piece of the input lives on disk.
struct WorkspaceLayout {
  // True for a dense workspace (--workspace_path), false for a sparse
  // model alone (--input_path).
  bool dense = false;
  // The model the estimate is made from (dense/sparse or --input_path).
  std::string model_path;
  // stereo/depth_maps of a dense workspace; empty in sparse mode.
  std::string depth_maps_path;
  // DP view folders; exactly one of right_path and sum_path is set.
  std::string left_path;
  std::string right_path;
  std::string sum_path;
};

// True if `dir` holds a COLMAP model (cameras, images, points3D as .bin or
// .txt).
bool IsModelDir(const std::string& dir);

// Checks that every path exists and has the pieces the run needs, and says
// which one is missing otherwise (InputError).
WorkspaceLayout ResolveWorkspaceLayout(const ScaleRunOptions& options);

}  // namespace dpsfm
