#include "dpsfm/exe/dp_psf_calibrator.h"

#include <cstdlib>
#include <ctime>
#include <iomanip>
#include <iostream>
#include <sstream>

#include <boost/filesystem.hpp>
#include <opencv2/imgproc.hpp>

#include "colmap/controllers/option_manager.h"
#include "colmap/util/logging.h"
#include "colmap/util/misc.h"
#include "colmap/util/timer.h"
#include "dpsfm/colmap/dp_images.h"
#include "dpsfm/colmap/psf_profile.h"
#include "dpsfm/colmap/workspace.h"
#include "dpsfm/core/blur_estimation.h"
#include "dpsfm/core/kernel_grid.h"
#include "dpsfm/core/lens_model.h"
#include "dpsfm/core/psf_calibration.h"

namespace fs = boost::filesystem;

namespace dpsfm {
namespace {

int Fail(const std::string& message) {
  std::cerr << "ERROR: dp_psf_calibrator: " << message << std::endl;
  return EXIT_FAILURE;
}

struct CalibratorOptions {
  std::string dp_image_path;
  std::string targets_path;
  std::string output_path;
  bool swap_dp_views = false;
  // Patch geometry on the working frame; 0 = DefaultPatchGeometry.
  int patch_size = 0;
  int stride = 0;
  double max_radius_px = 0;
  double min_texture_snr = 1.5;
  int max_patches_per_capture = 80;
  int num_threads = -1;
};

}  // namespace

int RunDPPsfCalibrator(int argc, char** argv) {
  CalibratorOptions options;
  colmap::OptionManager manager;
  manager.AddRequiredOption("dp_image_path",
                            &options.dp_image_path,
                            "folder with left/ and right/ (or sum/) DP views");
  manager.AddRequiredOption(
      "targets_path",
      &options.targets_path,
      "CSV: name,target_distance_m,focus_distance_m,focal_length_mm,"
      "f_number,pixel_pitch_um (pitch of the DP frames' pixels)");
  manager.AddRequiredOption(
      "output_path", &options.output_path, "profile file to write");
  manager.AddDefaultOption("DPPsfCalibrator.swap_dp_views",
                           &options.swap_dp_views,
                           "swap left and right DP views");
  manager.AddDefaultOption("DPPsfCalibrator.patch_size",
                           &options.patch_size,
                           "patch side in px of the working frame (0: auto)");
  manager.AddDefaultOption(
      "DPPsfCalibrator.stride", &options.stride, "patch stride (0: auto)");
  manager.AddDefaultOption("DPPsfCalibrator.max_radius_px",
                           &options.max_radius_px,
                           "blur radius search bound in px (0: auto)");
  manager.AddDefaultOption("DPPsfCalibrator.min_texture_snr",
                           &options.min_texture_snr,
                           "patches need this much texture over noise");
  manager.AddDefaultOption("DPPsfCalibrator.max_patches_per_capture",
                           &options.max_patches_per_capture,
                           "patches used per capture (evenly spread)");
  manager.AddDefaultOption("DPPsfCalibrator.num_threads",
                           &options.num_threads,
                           "threads (-1: all cores)");
  manager.Parse(argc, argv);

  try {
    colmap::Timer timer;
    timer.Start();
    colmap::PrintHeading1("DP PSF calibration");
    if (options.max_patches_per_capture < 1 ||
        !(options.min_texture_snr >= 0) ||
        (options.num_threads != -1 && options.num_threads < 1)) {
      throw InputError("invalid DPPsfCalibrator option values");
    }
    const std::vector<CalibrationTarget> targets =
        ReadCalibrationTargets(options.targets_path);
    WorkspaceLayout layout;
    layout.left_path = (fs::path(options.dp_image_path) / "left").string();
    const fs::path right = fs::path(options.dp_image_path) / "right";
    const fs::path sum = fs::path(options.dp_image_path) / "sum";
    if (!fs::is_directory(layout.left_path)) {
      throw InputError("no DP left views in " + layout.left_path);
    }
    if (fs::is_directory(right)) {
      layout.right_path = right.string();
    } else if (fs::is_directory(sum)) {
      layout.sum_path = sum.string();
    } else {
      throw InputError("neither right/ nor sum/ DP views in " +
                       options.dp_image_path);
    }
    const DPImageIndex index(layout);

    std::vector<ProfilePatch> patches;
    cv::Size frame_size;
    PatchGeometry geometry{};
    int border = 0;
    for (const CalibrationTarget& target : targets) {
      const DPFrames frames =
          LoadDPFrames(index.Find(target.name), options.swap_dp_views);
      if (frame_size.area() == 0) {
        frame_size = frames.left.size();
        geometry = DefaultPatchGeometry(frame_size);
        if (options.patch_size > 0) geometry.patch_size = options.patch_size;
        if (options.stride > 0) geometry.stride = options.stride;
        if (options.max_radius_px > 0) {
          geometry.max_radius_px = options.max_radius_px;
        }
        border = DPKernelGrid(TranslatingDiskPsf(),
                              BlurEstimationOptions().grid_step_px,
                              geometry.max_radius_px,
                              cv::Size())
                     .Border();
      } else if (frames.left.size() != frame_size) {
        throw InputError("capture " + target.name +
                         " differs in size from the first one (calibrate "
                         "one camera mode at a time)");
      }
      cv::Mat left = ToLuma(frames.left), right_view = ToLuma(frames.right);
      const double rf = geometry.resize_factor;
      if (rf < 1) {
        const cv::Size size(static_cast<int>(std::round(left.cols * rf)),
                            static_cast<int>(std::round(left.rows * rf)));
        cv::resize(left, left, size, 0, 0, cv::INTER_AREA);
        cv::resize(right_view, right_view, size, 0, 0, cv::INTER_AREA);
      }
      // The blur of the target in working-frame pixels (metric, s = 1).
      const double radius = PredictBlurRadiusPx(target.lens,
                                                target.lens.PixelPitchMm() / rf,
                                                1.0,
                                                target.focus_distance_m,
                                                target.target_distance_m);
      std::vector<ProfilePatch> found =
          ExtractProfilePatches(left,
                                right_view,
                                geometry.patch_size,
                                geometry.stride,
                                border,
                                radius,
                                options.min_texture_snr);
      const size_t textured = found.size();
      if (static_cast<int>(found.size()) > options.max_patches_per_capture) {
        std::vector<ProfilePatch> spread;
        for (int k = 0; k < options.max_patches_per_capture; ++k) {
          spread.push_back(
              found[k * found.size() / options.max_patches_per_capture]);
        }
        found.swap(spread);
      }
      std::ostringstream line;
      line << "  " << target.name << ": target " << target.target_distance_m
           << " m, focus " << target.focus_distance_m << " m, f "
           << target.lens.focal_length_mm << " mm f/" << target.lens.f_number
           << " -> blur radius " << std::fixed << std::setprecision(2) << radius
           << " px; " << textured << " textured patches";
      if (std::abs(radius) > geometry.max_radius_px - 0.5) {
        LOG(WARNING) << line.str() << ": beyond the search bound "
                     << geometry.max_radius_px << " px, skipped";
        continue;
      }
      LOG(INFO) << line.str() << ", " << found.size() << " used";
      patches.insert(patches.end(), found.begin(), found.end());
    }

    SplitProfileFitOptions fit_options;
    fit_options.blur.max_radius_px = geometry.max_radius_px;
    fit_options.num_threads = options.num_threads;
    colmap::PrintHeading2("Fitting the split profile");
    const SplitProfileCalibration calibration =
        CalibrateSplitProfile(patches, 3, fit_options);
    const SplitProfileFit& fit = calibration.frame;
    if (!fit.determined) {
      return Fail("the captures do not determine the profile: " + fit.reason +
                  ". Capture the target nearer or farther than the focus so "
                  "its blur is 3-15 px, with fine texture filling the frame");
    }
    LOG(INFO) << fit.reason;
    LOG(INFO) << "Median radius error with the fitted profile: " << std::fixed
              << std::setprecision(2) << 100 * fit.median_radius_error
              << " %; mean relative residual " << std::setprecision(6)
              << fit.mean_relative_residual;

    LOG(INFO) << calibration.summary;
    PsfProfileFile profile;
    profile.params = fit.params;
    if (calibration.banded) {
      for (const SplitProfileFit& band : calibration.bands) {
        profile.band_split_exponents.push_back(band.params.split_exponent);
      }
    }
    auto add = [&](const std::string& key, const std::string& value) {
      profile.fit_info.emplace_back("fit_" + key, value);
    };
    std::ostringstream v;
    add("captures", std::to_string(targets.size()));
    add("patches", std::to_string(fit.num_patches));
    v << fit.centroid_offset_ci_low << " " << fit.centroid_offset_ci_high;
    add("centroid_offset_ci95", v.str());
    v.str("");
    v << fit.centroid_offset << " (translating disk "
      << fit.translating_disk_centroid_offset << ")";
    add("centroid_offset_per_radius", v.str());
    v.str("");
    v << fit.median_radius_error;
    add("median_radius_error", v.str());
    v.str("");
    v << fit.mean_relative_residual;
    add("mean_relative_residual", v.str());
    add("frame_size",
        std::to_string(frame_size.width) + "x" +
            std::to_string(frame_size.height));
    {
      char date[32];
      const std::time_t now = std::time(nullptr);
      std::strftime(
          date, sizeof(date), "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
      add("created", date);
    }
    WritePsfProfile(options.output_path, profile);
    LOG(INFO) << "Profile: " << options.output_path << " (" << std::fixed
              << std::setprecision(1) << timer.ElapsedSeconds() << " s)";
    return EXIT_SUCCESS;
  } catch (const InputError& error) {
    return Fail(error.what());
  } catch (const std::exception& error) {
    return Fail(std::string("internal error: ") + error.what());
  }
}

}  // namespace dpsfm
