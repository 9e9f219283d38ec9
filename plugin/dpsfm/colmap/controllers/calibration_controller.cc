#include "dpsfm/colmap/controllers/calibration_controller.h"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "colmap/util/logging.h"
#include "colmap/util/timer.h"
#include "dpsfm/colmap/io/calibration_targets.h"
#include "dpsfm/colmap/io/dp_images.h"
#include "dpsfm/colmap/io/psf_profile.h"
#include "dpsfm/colmap/io/workspace.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "dpsfm/core/blur/blur_estimation.h"
#include "dpsfm/core/calibration/psf_calibration.h"
#include "dpsfm/core/calibration/shape_calibration.h"
#include "dpsfm/core/calibration/target_calibration.h"
#include "dpsfm/core/optics/encoding.h"
#include "dpsfm/core/optics/kernel_grid.h"
#include "dpsfm/core/optics/lens_model.h"
#include "dpsfm/core/util/check.h"

namespace fs = std::filesystem;

namespace dpsfm {

bool CalibrationRunOptions::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_VALUE(IsDPEncodingName(dp_encoding), dp_encoding);
  DPSFM_CHECK_OPTION_VALUE(
      transfer_uncertainty >= 0 && transfer_uncertainty < 1,
      transfer_uncertainty);
  DPSFM_CHECK_OPTION_GE(entrance_pupil_mm, 0);  // 0: the thin lens's
  DPSFM_CHECK_OPTION_GE(patch_size, 0);         // 0: auto
  DPSFM_CHECK_OPTION_GE(stride, 0);
  DPSFM_CHECK_OPTION_GE(max_radius_px, 0);
  DPSFM_CHECK_OPTION_GE(min_texture_snr, 0);
  DPSFM_CHECK_OPTION_GE(max_patches_per_capture, 1);
  DPSFM_CHECK_OPTION_GE(grid_rows, 1);
  DPSFM_CHECK_OPTION_GE(grid_cols, 1);
  DPSFM_CHECK_OPTION_GE(num_bootstrap, 10);
  DPSFM_CHECK_OPTION_VALUE(num_threads == -1 || num_threads > 0, num_threads);
  return true;
}

namespace {

// Patches evenly spread over the list, at most `count`.
std::vector<ProfilePatch> Spread(const std::vector<ProfilePatch>& found,
                                 int count) {
  if (static_cast<int>(found.size()) <= count) return found;
  std::vector<ProfilePatch> spread;
  for (int k = 0; k < count; ++k) {
    spread.push_back(found[k * found.size() / count]);
  }
  return spread;
}

// The stopped-down capture of the same target for each capture with blur:
// the same target distance (to 0.5 %) and a blur at most a third of its
// own. Then the shapes, on the strength fit's layout.
ShapeCalibration MeasureShapes(const std::vector<CalibrationTarget>& targets,
                               const TargetCalibration& calibration,
                               const std::vector<cv::Mat>& left,
                               const std::vector<cv::Mat>& right) {
  LOG_HEADING2("Measuring the kernels' shape");
  std::vector<ShapeCapture> captures;
  for (size_t i = 0; i < targets.size(); ++i) {
    const double r = calibration.capture_radius_px[i];
    int best = -1;
    for (size_t j = 0; j < targets.size(); ++j) {
      const double rj = calibration.capture_radius_px[j];
      if (j == i ||
          std::abs(targets[j].target_distance_m / targets[i].target_distance_m -
                   1) > 0.005 ||
          !(std::abs(rj) <= std::abs(r) / 3)) {
        continue;
      }
      if (best < 0 ||
          std::abs(rj) < std::abs(calibration.capture_radius_px[best])) {
        best = static_cast<int>(j);
      }
    }
    if (best < 0) continue;
    ShapeCapture capture;
    capture.name = targets[i].name;
    capture.left = left[i];
    capture.right = right[i];
    capture.sharp = left[best] + right[best];
    capture.signed_radius_px = r;
    LOG(INFO) << "  " << capture.name << " against " << targets[best].name
              << " (blur " << std::fixed << std::setprecision(2) << r
              << " px against " << calibration.capture_radius_px[best]
              << " px)";
    captures.push_back(std::move(capture));
  }
  ShapeCalibration shape;
  if (captures.empty()) {
    shape.reason =
        "no stopped-down capture of the same target to measure the shape "
        "against: add one at f/16 or more for each distance";
    LOG(INFO) << "  " << shape.reason;
    return shape;
  }
  ShapeCalibrationOptions options;
  options.layout = calibration.layout;
  shape = CalibrateShapes(captures, options);
  for (size_t i = 0; i < shape.capture_names.size(); ++i) {
    std::ostringstream line;
    line << "  " << shape.capture_names[i] << ": centroid offset per radius";
    for (const double o : shape.capture_cell_offsets[i]) {
      line << " " << std::setprecision(4) << o;
    }
    const cv::Point2d& shift = shape.capture_shifts[i];
    if (shift.x != 0 || shift.y != 0) {
      line << " (reference moved by " << shift.x << ", " << shift.y
           << " px to register it)";
    }
    if (!shape.capture_notes[i].empty()) {
      line << " (" << shape.capture_notes[i] << ")";
    }
    LOG(INFO) << line.str();
  }
  LOG(INFO) << "  " << shape.reason;
  return shape;
}

// The last line: the one number a profile is (its DP strength, defined in
// docs/psf-profiles.md), how well the captures measured it and what the
// scale inherits. Good under 5 % from the captures, usable under 10 %.
std::string CalibrationVerdict(double strength,
                               double own_uncertainty,
                               double transfer_uncertainty,
                               double uncertainty) {
  std::ostringstream line;
  line << std::setprecision(4) << "Verdict: DP strength " << strength
       << " (translating disk " << TranslatingDiskPsf::CentroidOffsetPerRadius()
       << ") +-" << std::fixed << std::setprecision(1) << 100 * own_uncertainty
       << " % from the captures: ";
  if (own_uncertainty <= 0.05) {
    line << "good";
  } else if (own_uncertainty <= 0.10) {
    line << "usable (add a capture farther from the focus to tighten it)";
  } else {
    line << "poor (capture the target at more distances, nearer and "
            "farther than the focus, with several pixels of blur)";
  }
  line << "; scales from this profile carry +-" << 100 * uncertainty << " % ("
       << 100 * transfer_uncertainty << " % for the transfer to scenes)";
  return line.str();
}

// Each capture's DP view files: the targets' left and right columns
// (relative to the captures folder), else left/<name> with right/<name> or
// sum/<name>.
std::vector<DPFramePaths> CaptureFiles(
    const std::string& dp_image_path,
    const std::vector<CalibrationTarget>& targets) {
  std::vector<DPFramePaths> files;
  if (!targets.empty() && !targets[0].left.empty()) {
    for (const CalibrationTarget& target : targets) {
      DPFramePaths paths;
      paths.left = (fs::path(dp_image_path) / target.left).string();
      paths.right = (fs::path(dp_image_path) / target.right).string();
      files.push_back(paths);
    }
    return files;
  }
  const std::string kLayouts =
      ": the captures go in left/<name> with right/<name> (or sum/<name>) "
      "under --dp_image_path, or targets.csv names each capture's files in "
      "left and right columns, relative to --dp_image_path (e.g. "
      "0600/f4/l.png and 0600/f4/r.png)";
  WorkspaceLayout layout;
  layout.left_path = (fs::path(dp_image_path) / "left").string();
  const fs::path right = fs::path(dp_image_path) / "right";
  const fs::path sum = fs::path(dp_image_path) / "sum";
  if (!fs::is_directory(layout.left_path)) {
    throw InputError("no folder " + layout.left_path + kLayouts);
  }
  if (fs::is_directory(right)) {
    layout.right_path = right.string();
  } else if (fs::is_directory(sum)) {
    layout.sum_path = sum.string();
  } else {
    throw InputError("neither right/ nor sum/ in " + dp_image_path + kLayouts);
  }
  const DPImageIndex index(layout);
  for (const CalibrationTarget& target : targets) {
    if (!index.HasLeft(target.name)) {
      throw InputError("no DP view " + target.name + " in " + layout.left_path +
                       kLayouts);
    }
    files.push_back(index.Find(target.name));
  }
  return files;
}

// The captures as the fit sees them: each one's patches on the working
// frame, and its grey working frames for the shape measurement.
struct WorkingCaptures {
  std::vector<CalibrationCapture> captures;
  std::vector<cv::Mat> grey_left, grey_right;
  cv::Size frame_size;
  PatchGeometry geometry{};
  // What the captures were given in (every capture alike, or said).
  std::set<std::string> frame_encodings;
};

// The working frame's patch geometry for captures of `frame_size`, and the
// border the weakest profile of the path needs at the search bound.
PatchGeometry CalibrationGeometry(const cv::Size& frame_size,
                                  const CalibrationRunOptions& options,
                                  int* border) {
  PatchGeometry geometry = DefaultPatchGeometry(frame_size);
  // Calibration targets are shot with several px of blur, and a weak split
  // reads it smaller still: the automatic bound is at least the phone's
  // 10 px (the frame-size rule gives 3.5 px for 512 px frames of a
  // downsampled full-frame sensor).
  if (options.max_radius_px <= 0 && geometry.max_radius_px < 10) {
    geometry = PatchGeometryForRadius(10, geometry.resize_factor);
  }
  if (options.patch_size > 0) geometry.patch_size = options.patch_size;
  if (options.stride > 0) geometry.stride = options.stride;
  if (options.max_radius_px > 0) geometry.max_radius_px = options.max_radius_px;
  *border = DPKernelGrid(TranslatingDiskPsf(),
                         BlurEstimationOptions().grid_step_px,
                         geometry.max_radius_px,
                         cv::Size())
                .Border();
  return geometry;
}

// The grey view, downsampled to the working frame (INTER_AREA).
cv::Mat WorkingGrey(const cv::Mat& view, double resize_factor) {
  cv::Mat grey = ToLuma(view);
  if (resize_factor < 1) {
    const cv::Size size(
        static_cast<int>(std::round(grey.cols * resize_factor)),
        static_cast<int>(std::round(grey.rows * resize_factor)));
    cv::resize(grey, grey, size, 0, 0, cv::INTER_AREA);
  }
  return grey;
}

// A target must fill the frame: at a distance that needs a plane wider than
// a wall (10 m), the distance is in another unit (600 for 0.6 m once read
// as "target 600 m", then "blur radius nan px" and a generic error).
// `sensor_width_mm`: the frame's width on the sensor.
void CheckTargetDistance(const CalibrationTarget& target,
                         double sensor_width_mm,
                         const CalibrationRunOptions& options) {
  const double d_m = target.target_distance_m;
  const double f_mm = target.lens.focal_length_mm;
  const double plane_m = d_m * sensor_width_mm / f_mm;
  if (!(plane_m > 10)) return;
  std::ostringstream s;
  s << std::setprecision(4) << options.targets_path << ":" << target.line
    << ": target_distance_m " << d_m << " puts " << target.name << "'s target "
    << d_m << " m away, where a plane filling the frame (" << sensor_width_mm
    << " mm of sensor behind " << f_mm << " mm) would be "
    << std::setprecision(3) << plane_m << " m wide: ";
  if (d_m >= 4 * f_mm) {  // as mm
    s << "is it in millimetres (" << d_m / 1000 << " m)? Give metres, or "
      << "write the unit (" << d_m << "mm)";
  } else if (10 * d_m >= 4 * f_mm) {  // as cm
    s << "is it in centimetres (" << d_m / 100 << " m)? Give metres, or "
      << "write the unit (" << d_m << "cm)";
  } else {
    s << "give the distance in metres from the focal-plane mark";
  }
  throw InputError(s.str());
}

// One capture's textured patches (at most max_patches_per_capture, spread
// over the frame) with its target's distances and lens.
CalibrationCapture MakeCapture(const CalibrationTarget& target,
                               const cv::Mat& left,
                               const cv::Mat& right,
                               const PatchGeometry& geometry,
                               int border,
                               const CalibrationRunOptions& options) {
  CalibrationCapture capture;
  capture.name = target.name;
  capture.lens = target.lens;
  capture.working_pitch_mm =
      target.lens.PixelPitchMm() / geometry.resize_factor;
  capture.target_distance_mm = 1000 * target.target_distance_m;
  capture.focus_distance_mm = 1000 * target.focus_distance_m;  // NaN stays
  capture.entrance_pupil_mm = options.entrance_pupil_mm;
  CheckTargetDistance(target, capture.working_pitch_mm * left.cols, options);
  if (options.entrance_pupil_mm > 0 &&
      !(capture.target_distance_mm - options.entrance_pupil_mm >
        2 * target.lens.focal_length_mm)) {
    throw InputError("target " + target.name + " at " +
                     std::to_string(target.target_distance_m) +
                     " m lies within two focal lengths of the entrance "
                     "pupil (--DPPsfCalibrator.entrance_pupil_mm " +
                     std::to_string(options.entrance_pupil_mm) +
                     " mm): check the option's unit (mm) and the distances");
  }
  const std::vector<ProfilePatch> found =
      ExtractProfilePatches(left,
                            right,
                            geometry.patch_size,
                            geometry.stride,
                            border,
                            std::numeric_limits<double>::quiet_NaN(),
                            options.min_texture_snr);
  capture.patches = Spread(found, options.max_patches_per_capture);
  LOG(INFO) << "  " << target.name << ": target " << target.target_distance_m
            << " m, focus "
            << (std::isnan(target.focus_distance_m)
                    ? std::string("unknown")
                    : std::to_string(target.focus_distance_m) + " m")
            << " (from the focal-plane mark), f " << target.lens.focal_length_mm
            << " mm f/" << target.lens.f_number << "; " << found.size()
            << " textured patches, " << capture.patches.size() << " used";
  return capture;
}

// Every capture read, brought to linear light and cut into patches; all
// captures must have one frame size (one camera mode).
WorkingCaptures LoadCaptures(const std::vector<CalibrationTarget>& targets,
                             const std::vector<DPFramePaths>& files,
                             const CalibrationRunOptions& options) {
  WorkingCaptures working;
  int border = 0;
  const DPEncoding requested_encoding = ParseDPEncoding(options.dp_encoding);
  for (size_t i = 0; i < targets.size(); ++i) {
    const CalibrationTarget& target = targets[i];
    const DPFrames frames =
        LoadDPFrames(files[i], options.swap_dp_views, requested_encoding);
    working.frame_encodings.insert(
        std::string(DPEncodingName(frames.encoding)) + " (" +
        frames.encoding_reason + ")");
    if (working.frame_size.area() == 0) {
      working.frame_size = frames.left.size();
      working.geometry =
          CalibrationGeometry(working.frame_size, options, &border);
    } else if (frames.left.size() != working.frame_size) {
      throw InputError("capture " + target.name +
                       " differs in size from the first one (calibrate "
                       "one camera mode at a time)");
    }
    const double rf = working.geometry.resize_factor;
    const cv::Mat left = WorkingGrey(frames.left, rf);
    const cv::Mat right = WorkingGrey(frames.right, rf);
    working.captures.push_back(
        MakeCapture(target, left, right, working.geometry, border, options));
    working.grey_left.push_back(left);
    working.grey_right.push_back(right);
  }
  return working;
}

// Each capture's blur at the focus used and the DP strength it reads alone.
void LogCaptureFits(const TargetCalibration& calibration) {
  for (size_t i = 0; i < calibration.capture_names.size(); ++i) {
    const double kappa = calibration.capture_centroid_offset[i];
    std::ostringstream own;
    if (std::isfinite(kappa)) {
      own << "its own DP strength " << std::setprecision(4) << kappa;
    } else {
      own << "too little blur to read a DP strength (a sharp reference, "
             "used for the kernels' shape)";
    }
    if (!std::isfinite(calibration.capture_radius_px[i])) {
      // No focus made the captures agree: the thin lens gives no blur.
      LOG(INFO) << "  " << calibration.capture_names[i]
                << ": blur radius not known (no focus distance makes the "
                   "captures' blur agree with their distances; see below), "
                   "read as "
                << std::fixed << std::setprecision(2)
                << calibration.capture_reading_px[i]
                << " px by the linear split";
      continue;
    }
    LOG(INFO) << "  " << calibration.capture_names[i] << ": blur radius "
              << std::fixed << std::setprecision(2)
              << calibration.capture_radius_px[i]
              << " px at the focus used, read as "
              << calibration.capture_reading_px[i]
              << " px by the linear split; " << own.str();
  }
}

// The fit of the DP profile over the captures' patches.
TargetCalibration FitProfile(const std::vector<CalibrationCapture>& captures,
                             const PatchGeometry& geometry,
                             const CalibrationRunOptions& options) {
  TargetCalibrationOptions fit_options;
  fit_options.blur.max_radius_px = geometry.max_radius_px;
  fit_options.grid_rows = options.grid_rows;
  fit_options.grid_cols = options.grid_cols;
  fit_options.num_bootstrap = options.num_bootstrap;
  fit_options.num_threads = options.num_threads;
  std::string failure;
  if (!fit_options.Check(&failure)) {
    throw InputError("invalid calibration options: " + failure);
  }
  LOG_HEADING2("Fitting the DP profile");
  const TargetCalibration calibration =
      CalibrateFromTargets(captures, fit_options);
  LogCaptureFits(calibration);
  return calibration;
}

// The profile's kernels: each cell's measured (deconvolved) kernels where
// the shape was measured, else the split family's at the fitted strength;
// at the search bound, far side (the estimator magnifies them for every
// other radius). Returns the fit's own relative uncertainty: the overall
// strength's interval and, where the shape was measured, the two
// measurements' disagreement (the blur readings' strength and the
// deconvolved kernels' own).
double AddProfileKernels(const TargetCalibration& calibration,
                         const ShapeCalibration& shape,
                         PsfProfileFile* profile) {
  double uncertainty =
      std::max(calibration.strength - calibration.strength_ci_low,
               calibration.strength_ci_high - calibration.strength) /
      calibration.strength;
  if (shape.determined) {
    profile->reference_radius_px = shape.reference_radius_px;
    for (const DPKernels& k : shape.cell_kernels) {
      profile->left_kernels.push_back(k.left);
      profile->right_kernels.push_back(k.right);
    }
    const double shape_strength =
        MeasuredStrength(shape, calibration.cell_patches);
    uncertainty = std::max(uncertainty,
                           std::abs(shape_strength / calibration.strength - 1));
    LOG(INFO) << "Measured shape: the deconvolved kernels' DP strength "
              << std::setprecision(4) << shape_strength << " against "
              << calibration.strength
              << " from the blur readings (their difference counts in "
                 "the uncertainty)";
    return uncertainty;
  }
  for (int c = 0; c < calibration.layout.NumCells(); ++c) {
    const DPKernels k =
        SplitProfilePsf(SplitProfileParams::ForCentroidOffset(
                            calibration.cell_centroid_offsets[c]))
            .Kernels(profile->reference_radius_px);
    profile->left_kernels.push_back(k.left);
    profile->right_kernels.push_back(k.right);
  }
  return uncertainty;
}

// The profile's fit_* lines: what was fitted from what, for people and for
// the report of every run that uses the profile.
void AddFitInfo(const TargetCalibration& calibration,
                const ShapeCalibration& shape,
                const WorkingCaptures& working,
                double own_uncertainty,
                const CalibrationRunOptions& options,
                PsfProfileFile* profile) {
  auto add = [&](const std::string& key, const std::string& value) {
    profile->fit_info.emplace_back("fit_" + key, value);
  };
  std::ostringstream v;
  v << std::setprecision(4);
  add("summary", calibration.reason);
  add("captures", std::to_string(working.captures.size()));
  v << own_uncertainty << " from the captures, " << options.transfer_uncertainty
    << " for the transfer to scenes (in quadrature: " << profile->uncertainty
    << ")";
  add("uncertainty_terms", v.str());
  v.str("");
  v << calibration.focus_distance_mm / 1000 << " m from the focal-plane mark"
    << (calibration.focus_fitted ? " (fitted; 95 % interval " : " (given")
    << (calibration.focus_fitted
            ? std::to_string(calibration.focus_ci_low_mm / 1000) + " - " +
                  std::to_string(calibration.focus_ci_high_mm / 1000) + " m)"
            : ")");
  add("focus_distance", v.str());
  v.str("");
  if (options.entrance_pupil_mm > 0) {
    v << "entrance pupil, " << options.entrance_pupil_mm
      << " mm in front of the focal-plane mark";
  } else {
    v << "the thin lens focused at the fitted focus (entrance pupil not "
         "given)";
  }
  add("distance_origin", v.str());
  v.str("");
  for (int c = 0; c < calibration.layout.NumCells(); ++c) {
    v << (c ? " " : "") << calibration.cell_centroid_offsets[c];
  }
  add("cell_centroid_offsets", v.str());
  v.str("");
  v << calibration.centroid_offset << " (translating disk "
    << TranslatingDiskPsf::CentroidOffsetPerRadius() << ")";
  add("centroid_offset_per_radius", v.str());
  add("shape",
      shape.determined
          ? "measured by deconvolution: " + shape.reason
          : "the split family's at the fitted strength" +
                (shape.reason.empty() ? std::string()
                                      : " (" + shape.reason + ")"));
  std::string encodings;
  for (const std::string& e : working.frame_encodings) {
    encodings += (encodings.empty() ? "" : ", ") + e;
  }
  add("frames_encoding", encodings + ", brought to linear light");
  add("frame_size",
      std::to_string(working.frame_size.width) + "x" +
          std::to_string(working.frame_size.height));
  char date[32];
  const std::time_t now = std::time(nullptr);
  std::strftime(date, sizeof(date), "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&now));
  add("created", date);
}

// The radius of a measured kernel pair's light (left + right): sqrt(2 E[rho^2])
// about its centroid, the radius of a uniform disk with the same second
// moment.
double KernelRadiusPx(const DPKernels& k) {
  const cv::Mat sum = k.left + k.right;
  const int c = sum.rows / 2;
  double w = 0, x = 0, y = 0;
  for (int i = 0; i < sum.rows; ++i) {
    for (int j = 0; j < sum.cols; ++j) {
      const double v = std::max(0.0f, sum.at<float>(i, j));
      w += v;
      x += v * (j - c);
      y += v * (i - c);
    }
  }
  if (!(w > 0)) return std::numeric_limits<double>::quiet_NaN();
  x /= w;
  y /= w;
  double r2 = 0;
  for (int i = 0; i < sum.rows; ++i) {
    for (int j = 0; j < sum.cols; ++j) {
      const double v = std::max(0.0f, sum.at<float>(i, j));
      r2 += v * ((j - c - x) * (j - c - x) + (i - c - y) * (i - c - y));
    }
  }
  return std::sqrt(2 * r2 / w);
}

// The captures with blur (those that read a DP strength).
std::vector<size_t> BlurredCaptures(const TargetCalibration& calibration) {
  std::vector<size_t> blurred;
  for (size_t i = 0; i < calibration.capture_centroid_offset.size(); ++i) {
    if (std::isfinite(calibration.capture_centroid_offset[i])) {
      blurred.push_back(i);
    }
  }
  return blurred;
}

// The one value of a lens number the blurred captures share (0: they
// differ by more than 1 %, or none has blur).
double SharedValue(const std::vector<CalibrationTarget>& targets,
                   const std::vector<size_t>& blurred,
                   double DPLensData::* member) {
  double value = 0;
  for (const size_t i : blurred) {
    const double v = targets[i].lens.*member;
    if (value == 0) {
      value = v;
    } else if (std::abs(v / value - 1) > 0.01) {
      return 0;
    }
  }
  return value;
}

// The thin lens against the measured kernels: their light spreads over the
// blur the captures really had, whatever the DP split; the strength fit
// cannot see a wrong f-number (blur and strength trade one for the other),
// the kernels can. Real kernels read up to ~15 % small on this measure
// (soft rims; R6 II at f/4: 0.87 of the thin lens), so 2/3 stop is allowed.
// Throws InputError naming the f-number (and the other numbers the thin
// lens uses) when the kernels are farther off.
void CheckThinLens(const std::vector<CalibrationTarget>& targets,
                   const TargetCalibration& calibration,
                   const ShapeCalibration& shape,
                   const CalibrationRunOptions& options) {
  const std::vector<size_t> blurred = BlurredCaptures(calibration);
  const double f_number = SharedValue(targets, blurred, &DPLensData::f_number);
  if (!shape.determined || shape.cell_kernels.empty()) {
    LOG(INFO) << "The f-number and focal length are not checked against the "
                 "captures' blur: that needs the kernels' shape, measured "
                 "against stopped-down (f/16 or more) captures of the same "
                 "targets";
    return;
  }
  std::vector<double> radii;
  for (const DPKernels& k : shape.cell_kernels) {
    const double r = KernelRadiusPx(k);
    if (std::isfinite(r)) radii.push_back(r);
  }
  if (radii.empty() || f_number <= 0) return;
  std::sort(radii.begin(), radii.end());
  const double measured = radii[radii.size() / 2];
  const double ratio = measured / shape.reference_radius_px;
  const double implied = f_number / ratio;
  const double tolerance = std::log(2.0) / 3;  // 2/3 stop in N
  std::ostringstream s;
  s << std::setprecision(3) << "The captures' blur against the thin lens: "
    << "the measured kernels spread over " << measured << " px where f/"
    << f_number << " predicts " << shape.reference_radius_px << " px (ratio "
    << ratio << ", as f/" << implied << " would make it)";
  LOG(INFO) << s.str();
  if (std::abs(std::log(ratio)) <= tolerance) return;
  const CalibrationTarget& t = targets[blurred.front()];
  std::ostringstream e;
  e << std::setprecision(4) << "the captures' blur disagrees with the thin "
    << "lens at f/" << f_number << ": the kernels measured against the "
    << "stopped-down references spread over " << std::setprecision(3)
    << measured << " px where f/" << f_number << ", " << std::setprecision(4)
    << t.lens.focal_length_mm << " mm and " << t.lens.pixel_pitch_um
    << " um at the fitted focus predict " << std::setprecision(3)
    << shape.reference_radius_px << " px, as f/" << std::setprecision(2)
    << implied << " would make them (more than 2/3 stop off): correct "
    << "f_number in " << options.targets_path
    << " (or focal_length_mm, pixel_pitch_um); a profile fitted to them "
       "would be "
    << std::setprecision(0) << std::fixed << 100 * std::abs(1 - ratio)
    << " % too " << (ratio < 1 ? "weak" : "strong");
  throw InputError(e.str());
}

// What the profile was measured under, for the estimator's check.
ProfileConditions MeasuredConditions(
    const std::vector<CalibrationTarget>& targets,
    const TargetCalibration& calibration,
    const WorkingCaptures& working) {
  ProfileConditions c;
  const std::vector<size_t> blurred = BlurredCaptures(calibration);
  c.focal_length_mm =
      SharedValue(targets, blurred, &DPLensData::focal_length_mm);
  c.f_number = SharedValue(targets, blurred, &DPLensData::f_number);
  c.pixel_pitch_um = SharedValue(targets, blurred, &DPLensData::pixel_pitch_um);
  c.frame_width = working.frame_size.width;
  c.frame_height = working.frame_size.height;
  const double rf = working.geometry.resize_factor;
  for (const size_t i : blurred) {
    const double r = std::abs(calibration.capture_radius_px[i]) / rf;
    c.min_blur_px = c.min_blur_px == 0 ? r : std::min(c.min_blur_px, r);
    c.max_blur_px = std::max(c.max_blur_px, r);
  }
  if (c.f_number == 0 && !blurred.empty()) {
    LOG(WARNING) << "The captures with blur differ in f-number: the profile "
                    "records none, and the estimator cannot check it";
  }
  return c;
}

}  // namespace

RunOutcome RunPsfCalibration(const CalibrationRunOptions& options) {
  colmap::Timer timer;
  timer.Start();
  LOG_HEADING1("DP PSF calibration");
  std::string failure;
  if (!options.Check(&failure)) {
    throw InputError("invalid --DPPsfCalibrator option: " + failure);
  }
  const std::vector<CalibrationTarget> targets =
      ReadCalibrationTargets(options.targets_path);
  const WorkingCaptures working = LoadCaptures(
      targets, CaptureFiles(options.dp_image_path, targets), options);
  const TargetCalibration calibration =
      FitProfile(working.captures, working.geometry, options);
  if (!calibration.determined) {
    return RunOutcome::Failure(
        "the captures do not determine the DP profile: " + calibration.reason +
        ". Capture the textured target (filling the frame) at two or more "
        "distances nearer and farther than the focus, so that its blur is "
        "several pixels");
  }
  LOG(INFO) << calibration.reason;
  LOG(INFO) << "Fitted in " << std::fixed << std::setprecision(1)
            << calibration.seconds << " s";

  const ShapeCalibration shape =
      options.measure_shape
          ? MeasureShapes(
                targets, calibration, working.grey_left, working.grey_right)
          : ShapeCalibration();
  CheckThinLens(targets, calibration, shape, options);

  PsfProfileFile profile;
  profile.model = "measured_kernels";
  profile.reference_radius_px = working.geometry.max_radius_px;
  profile.far_side = true;
  profile.layout = calibration.layout;
  profile.camera = options.camera;
  profile.lens = options.lens;
  profile.conditions = MeasuredConditions(targets, calibration, working);
  const double own_uncertainty =
      AddProfileKernels(calibration, shape, &profile);
  // What the scale inherits: the fit's own uncertainty and how far a
  // calibration on planes transfers to scenes, in quadrature.
  profile.uncertainty =
      std::hypot(own_uncertainty, options.transfer_uncertainty);
  profile.light = "linear";
  AddFitInfo(calibration, shape, working, own_uncertainty, options, &profile);
  WritePsfProfile(options.output_path, profile);
  LOG(INFO) << "Profile: " << options.output_path << " ("
            << calibration.layout.ToString() << " of measured kernels at "
            << profile.reference_radius_px
            << " px; its .npy kernel files are beside it; " << std::fixed
            << std::setprecision(1) << timer.ElapsedSeconds() << " s)";
  LOG(INFO) << CalibrationVerdict(calibration.strength,
                                  own_uncertainty,
                                  options.transfer_uncertainty,
                                  profile.uncertainty);
  return RunOutcome::Success();
}

}  // namespace dpsfm
