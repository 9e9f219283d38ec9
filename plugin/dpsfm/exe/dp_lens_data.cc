#include "dpsfm/exe/dp_lens_data.h"

#include <cstdlib>
#include <iostream>

#include "dpsfm/colmap/controllers/lens_data_controller.h"
#include "dpsfm/exe/command_boundary.h"
#include "dpsfm/exe/command_options.h"

namespace dpsfm {

int RunDPLensData(int argc, char** argv) {
  LensDataRunOptions options;
  CommandOptions manager(
      "dp_lens_data",
      "Lists each image's lens data as dp_scale_estimator will read it: "
      "focal length, f-number, pixel pitch, recorded focus, camera and lens, "
      "from lens.csv, the flags, the original image's metadata (EXIF and "
      "maker notes of JPEG, TIFF, PNG, raw, CR3 and HEIF files) or its DP "
      "frame's, with the source of every cell. Printed as a lens.csv, or "
      "written to --output_path: correct what is wrong in it and give it to "
      "dp_scale_estimator as --lens_path.",
      {"--workspace_path dense --image_path images --output_path lens.csv",
       "--input_path sparse/0 --image_path images --dp_image_path dp",
       "--image_path images"});
  manager.Group("Images");
  manager.AddDefault("workspace_path",
                     &options.workspace_path,
                     "dense workspace: its sparse model names the images "
                     "and their cameras");
  manager.AddDefault("input_path",
                     &options.input_path,
                     "sparse model instead of a dense workspace");
  manager.AddDefault("image_path",
                     &options.image_path,
                     "original images, read for their metadata; without a "
                     "model every file under it is listed");
  manager.AddDefault("dp_image_path",
                     &options.dp_image_path,
                     "DP views (left/<name>): a frame's own metadata fills "
                     "what the original image does not record");
  manager.Group("Lens data (as dp_scale_estimator's)");
  manager.AddDefault("lens_path",
                     &options.lens_path,
                     "lens.csv whose cells win over the images' metadata");
  manager.AddDefault("DPScaleEstimator.focal_length_mm",
                     &options.focal_length_mm,
                     "focal length in millimetres for every image (0: not "
                     "given)");
  manager.AddDefault("DPScaleEstimator.f_number",
                     &options.f_number,
                     "f-number for every image (0: not given)");
  manager.AddDefault("DPScaleEstimator.pixel_pitch_um",
                     &options.pixel_pitch_um,
                     "pixel pitch in micrometres of the model camera's "
                     "pixels (0: not given)");
  manager.AddDefault("DPScaleEstimator.use_recorded_focus",
                     &options.use_recorded_focus,
                     "use the focus distance recorded in the images' "
                     "metadata");
  manager.AddDefault("DPScaleEstimator.lens_check_tolerance",
                     &options.lens_check_tolerance,
                     "as dp_scale_estimator's: how far f_mm / pitch may "
                     "differ from the camera's f_px beyond focus breathing");
  manager.Group("Output");
  manager.AddDefault("output_path",
                     &options.output_path,
                     "lens.csv to write (never over an existing file); "
                     "empty: printed");
  int exit_code = EXIT_SUCCESS;
  if (!manager.Parse(argc, argv, std::cout, &exit_code)) return exit_code;

  return RunAtCommandBoundary(
      "dp_lens_data", [&] { return RunLensData(options, std::cout); });
}

}  // namespace dpsfm
