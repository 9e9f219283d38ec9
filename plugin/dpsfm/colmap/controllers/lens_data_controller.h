// The run of `colmap dp_lens_data` (RunLensData): every image of a model,
// or every image file under a folder, read as dp_scale_estimator reads it
// (lens.csv, the flags, the original image's metadata, then its DP frame's,
// the pitch derived from the model's camera) and listed as a lens.csv with
// the source of every cell, so that a user sees before a run what it will
// use and can correct it by editing the file and passing it as
// --lens_path.
#pragma once

#include <iosfwd>
#include <string>

#include "dpsfm/colmap/controllers/run_outcome.h"

namespace dpsfm {

struct LensDataRunOptions {
  // The images and their cameras: a dense workspace (its sparse model,
  // dense/sparse), or a sparse model; neither: every file under image_path
  // (no camera, so no pitch derived or checked).
  std::string workspace_path;
  std::string input_path;
  // The original images (their metadata).
  std::string image_path;
  // The DP views: left/<name> frames' metadata, after the original's.
  std::string dp_image_path;
  // A lens.csv whose cells win, as in a run.
  std::string lens_path;
  // The lens.csv to write (never over an existing file); empty: printed.
  std::string output_path;
  // As dp_scale_estimator's flags of the same names.
  double focal_length_mm = 0;
  double f_number = 0;
  double pixel_pitch_um = 0;
  bool use_recorded_focus = true;
  double lens_check_tolerance = 0.1;

  // False at the first invalid option, which *failure (when given) names
  // with its value (core/util/check.h).
  bool Check(std::string* failure = nullptr) const;
};

// Lists the images' lens data: printed to `out`, or written to
// output_path. Throws InputError for what the user must fix (no images, a
// path that is not there, an output file that exists).
RunOutcome RunLensData(const LensDataRunOptions& options, std::ostream& out);

}  // namespace dpsfm
