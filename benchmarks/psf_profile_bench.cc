// DP PSF profiles x estimation modes: synthetic multi-view captures
// rendered with split profiles that differ from the translating disk, and
// with measured-kernel sensors outside every family the estimator fits
// (elliptical, rotated, cat-eye with a bright rim, kernels changing across
// the frame), estimated with the translating disk, with the self-calibrated
// profile (`auto`) and with a profile calibrated from separate captures of
// a planar target made with the same simulated camera (`calibrated`,
// CalibrateFromTargets with the focus unknown). Prints r_s = s_est / s_true per
// scene, e_s per profile and mode, and the runtime of `auto` against
// `translating_disk`. Prints figures; never asserts.
//
//   psf_profile_bench [--scenes N] [--views V] [--noise SIGMA] [--only NAME]
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "../tests/core/synthetic_dp.h"
#include "bench_timing.h"
#include "dpsfm/core/calibration/psf_calibration.h"
#include "dpsfm/core/calibration/shape_calibration.h"
#include "dpsfm/core/calibration/target_calibration.h"
#include "dpsfm/core/scale/scale_estimator.h"

namespace {

using namespace dpsfm;

constexpr int kWidth = 640;
constexpr int kHeight = 480;

using bench::Now;

// A simulated sensor: a profile, or two blended across the frame (the split
// changes linearly from `psf` at the left edge to `right_edge` at the right).
struct Sensor {
  std::string name;
  std::shared_ptr<const DPPsfModel> psf;
  std::shared_ptr<const DPPsfModel> right_edge;  // null = uniform
};

test::DPPair Render(const cv::Mat& sharp,
                    const Sensor& sensor,
                    const cv::Mat& radius,
                    const test::RenderOptions& render) {
  test::RenderOptions clean;
  test::DPPair pair = test::RenderDP(sharp, *sensor.psf, radius, clean);
  if (sensor.right_edge) {
    const test::DPPair other =
        test::RenderDP(sharp, *sensor.right_edge, radius, clean);
    cv::Mat weight(sharp.size(), CV_32FC1);
    for (int x = 0; x < sharp.cols; ++x) {
      weight.col(x).setTo(static_cast<float>(x) / (sharp.cols - 1));
    }
    cv::Mat w3;
    cv::merge(std::vector<cv::Mat>(sharp.channels(), weight), w3);
    const cv::Mat one_minus = cv::Scalar::all(1.0) - w3;
    pair.left = pair.left.mul(one_minus) + other.left.mul(w3);
    pair.right = pair.right.mul(one_minus) + other.right.mul(w3);
  }
  test::internal::FinishViews(render, &pair);
  return pair;
}

DPLensData Lens(double f, double n) {
  DPLensData lens;
  lens.focal_length_mm = f;
  lens.f_number = n;
  lens.pixel_pitch_um = 10;
  return lens;
}

// One capture: bands of constant depth plus a nearer rectangle.
DPView Capture(
    const Sensor& sensor, int scene, int position, double scale, double noise) {
  const DPLensData lens = position % 2 ? Lens(50, 2.8) : Lens(35, 2);
  const double focus_m = 1.8 + 0.1 * (position % 4);
  test::TextureOptions tex;
  tex.channels = 3;
  const cv::Mat sharp = test::MakeTexture(
      cv::Size(kWidth, kHeight), 5000 + 100 * scene + position, tex);
  const double depths_m[] = {1.45, 1.75, 2.1, 2.6, 3.1, 3.5};
  cv::Mat depth_m(kHeight, kWidth, CV_32FC1);
  for (int x = 0; x < kWidth; ++x) {
    const int band = x * 6 / kWidth;
    depth_m.col(x).setTo(depths_m[(band * 5 + position * 3 + scene) % 6]);
  }
  depth_m(cv::Rect(kWidth / 3, kHeight / 2, kWidth / 3, kHeight / 3))
      .setTo(1.3 + 0.1 * (position % 3));
  cv::Mat radius(kHeight, kWidth, CV_32FC1);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      radius.at<float>(y, x) = static_cast<float>(PredictBlurRadiusPx(
          lens, lens.PixelPitchMm(), 1.0, focus_m, depth_m.at<float>(y, x)));
    }
  }
  test::RenderOptions render;
  render.noise_sigma = noise;
  render.noise_seed = 7000 + 100 * scene + position;
  const test::DPPair pair = Render(sharp, sensor, radius, render);
  DPView view;
  view.name = "view" + std::to_string(position);
  view.left = pair.left;
  view.right = pair.right;
  view.lens = lens;
  cv::resize(depth_m / scale,
             view.depth,
             cv::Size(kWidth / 2, kHeight / 2),
             0,
             0,
             cv::INTER_NEAREST);
  return view;
}

DPScaleOptions Options() {
  DPScaleOptions options;
  options.geometry.patch_size = 51;
  options.geometry.stride = 20;
  options.geometry.max_radius_px = 10;
  options.geometry.resize_factor = 1;
  return options;
}

// `calibrated`: a textured plane shot by the same simulated camera (50 mm
// f/8, focus 1.0 m from the sensor, left unknown to the calibration) at
// six distances from the focal-plane mark, calibrated with
// CalibrateFromTargets in three column bands; the field of the fitted
// profiles.
struct Calibrated {
  DPPsfField family, shape;  // empty = refused
  double family_uncertainty = 0, shape_uncertainty = 0;
  std::string note;
};

// The calibration camera: 50 mm f/8 focused 1.0 m from the sensor.
constexpr double kCalibrationFocusMm = 1000;

// The signed blur radius (pixels) of the target d mm from the focal-plane
// mark, through the calibration camera.
double TargetBlurRadiusPx(const DPLensData& lens, double d) {
  const double focus_mm = kCalibrationFocusMm;
  const double u_g = FocusObjectDistanceMm(focus_mm, lens.focal_length_mm);
  return BlurRadiusPxFromDiameterMm(
      SignedBlurDiameterMm(
          lens,
          u_g,
          ObjectDistanceFromSensorMm(d, focus_mm, lens.focal_length_mm)),
      lens.PixelPitchMm());
}

// Capture k of the target d mm away: its profile patches for the family,
// and for the shape its grey views and a stopped-down (f/32) capture of
// the same target.
void ShootTarget(const Sensor& sensor,
                 const DPLensData& lens,
                 double d,
                 int k,
                 double noise,
                 std::vector<CalibrationCapture>* captures,
                 std::vector<ShapeCapture>* shape_captures) {
  const DPScaleOptions options = Options();
  const int border = 11;  // KernelRadius(10) of the split family
  CalibrationCapture capture;
  capture.name = std::to_string(static_cast<int>(d)) + " mm";
  capture.lens = lens;
  capture.working_pitch_mm = lens.PixelPitchMm();
  capture.target_distance_mm = d;
  const double r = TargetBlurRadiusPx(lens, d);
  test::TextureOptions tex;
  tex.channels = 3;
  const cv::Mat sharp =
      test::MakeTexture(cv::Size(kWidth, kHeight), 9000 + k, tex);
  test::RenderOptions render;
  render.noise_sigma = noise;
  render.noise_seed = 9100 + k;
  const test::DPPair pair = Render(
      sharp, sensor, cv::Mat(kHeight, kWidth, CV_32FC1, cv::Scalar(r)), render);
  capture.patches = ExtractProfilePatches(test::ToGray(pair.left),
                                          test::ToGray(pair.right),
                                          options.geometry.patch_size,
                                          30,
                                          border,
                                          std::nan(""),
                                          1.5);
  captures->push_back(std::move(capture));
  test::RenderOptions sharp_render = render;
  sharp_render.noise_seed += 50;
  const test::DPPair stopped =
      Render(sharp,
             sensor,
             cv::Mat(kHeight, kWidth, CV_32FC1, cv::Scalar(r * 8 / 32)),
             sharp_render);
  ShapeCapture shape;
  shape.name = captures->back().name;
  shape.left = test::ToGray(pair.left);
  shape.right = test::ToGray(pair.right);
  shape.sharp = test::ToGray(stopped.left) + test::ToGray(stopped.right);
  shape_captures->push_back(std::move(shape));
}

// The family's profiles per cell and their uncertainty, as
// dp_psf_calibrator writes them into the profile file.
void SetFamily(const TargetCalibration& c, Calibrated* out) {
  out->family_uncertainty = std::max(c.strength - c.strength_ci_low,
                                     c.strength_ci_high - c.strength) /
                            c.strength;
  out->family.layout = c.layout;
  for (const double kappa : c.cell_centroid_offsets) {
    out->family.cells.push_back(std::make_shared<const SplitProfilePsf>(
        SplitProfileParams::ForCentroidOffset(kappa)));
  }
}

// The shape, measured at the radii the fitted focus gives: its kernels per
// cell and their uncertainty (none if it is not determined).
void MeasureShape(const TargetCalibration& c,
                  std::vector<ShapeCapture> shape_captures,
                  Calibrated* out) {
  for (size_t i = 0; i < shape_captures.size(); ++i) {
    shape_captures[i].signed_radius_px = c.capture_radius_px[i];
  }
  ShapeCalibrationOptions shape_options;
  shape_options.layout = c.layout;
  const ShapeCalibration shape = CalibrateShapes(shape_captures, shape_options);
  out->note += "; shape: " + shape.reason;
  if (!shape.determined) return;
  out->shape.layout = c.layout;
  for (size_t cell = 0; cell < shape.cell_kernels.size(); ++cell) {
    out->shape.cells.push_back(std::make_shared<const MeasuredKernelPsf>(
        shape.cell_kernels[cell].left,
        shape.cell_kernels[cell].right,
        shape.reference_radius_px,
        true));
  }
  out->shape_uncertainty = std::max(
      out->family_uncertainty,
      std::abs(MeasuredStrength(shape, c.cell_patches) / c.strength - 1));
}

Calibrated Calibrate(const Sensor& sensor, double noise) {
  const DPLensData lens = Lens(50, 8);
  std::vector<CalibrationCapture> captures;
  std::vector<ShapeCapture> shape_captures;
  int k = 0;
  for (const double d : {700.0, 800.0, 880.0, 1250.0, 1600.0, 2400.0}) {
    ShootTarget(sensor, lens, d, k++, noise, &captures, &shape_captures);
  }
  TargetCalibrationOptions fit;
  fit.blur.max_radius_px = Options().geometry.max_radius_px;
  fit.grid_rows = 1;
  fit.grid_cols = 3;
  const TargetCalibration c = CalibrateFromTargets(captures, fit);
  Calibrated out;
  out.note = c.reason;
  if (!c.determined) return out;
  SetFamily(c, &out);
  MeasureShape(c, std::move(shape_captures), &out);
  return out;
}

struct Run {
  bool success = false;
  bool holds = false;  // the interval holds the truth
  double ratio = 0, seconds = 0;
  std::string note;
};

Run Estimate(const std::vector<DPView>& views,
             const DPPsfField& field,
             bool self_calibration,
             double scale,
             double profile_uncertainty = 0) {
  DPScaleOptions options = Options();
  options.self_calibration.mode = self_calibration
                                      ? SelfCalibrationOptions::Mode::kFit
                                      : SelfCalibrationOptions::Mode::kOff;
  options.interval.profile_relative_uncertainty = profile_uncertainty;
  // Renders of a thin lens: no lens-geometry term.
  options.interval.lens_geometry_uncertainty = 0;
  const double t0 = Now();
  DPScaleEstimator estimator(options, field);
  for (const DPView& view : views) estimator.AddView(view);
  const DPScaleResult result = estimator.Estimate();
  Run run;
  run.seconds = Now() - t0;
  run.success = result.success;
  run.ratio = result.success ? result.scale / scale : 0;
  run.holds = result.success && result.scale_ci_low <= scale &&
              scale <= result.scale_ci_high;
  // The refusal's code only: its sentence is the COLMAP layer's
  // (colmap/report/refusal_text), which benchmarks do not link.
  run.note = result.success ? result.psf.status
                            : ScaleRefusalName(result.refusal.code);
  return run;
}

// The command line.
struct BenchArguments {
  int num_scenes = 2, num_views = 8;
  double noise = 0.005;
  std::string only;  // run only the sensors whose name contains this
};

// The modes: translating_disk, auto, calibrated, calibrated shape.
constexpr int kModes = 4;

// One sensor's row of the table: r_s per mode (scenes joined by ", "), and
// the sums of |1 - r_s| over the answers.
struct Row {
  std::string cells[kModes];
  double errors[kModes] = {0, 0, 0, 0};
  int counts[kModes] = {0, 0, 0, 0};
};

// What the summary after the table reads, over all sensors.
struct Totals {
  double time_disk = 0, time_auto = 0;
  std::vector<std::string> notes;
  int held[kModes] = {0, 0, 0, 0}, answered[kModes] = {0, 0, 0, 0};
  std::vector<std::string> calibration_notes;
};

// Reads the flags; false, with a message, on an unknown flag.
bool ParseArguments(int argc, char** argv, BenchArguments* args) {
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--scenes") {
      args->num_scenes = std::atoi(argv[i + 1]);
    } else if (flag == "--views") {
      args->num_views = std::atoi(argv[i + 1]);
    } else if (flag == "--noise") {
      args->noise = std::atof(argv[i + 1]);
    } else if (flag == "--only") {
      args->only = argv[i + 1];
    } else {
      std::fprintf(stderr, "unknown flag %s\n", argv[i]);
      return false;
    }
  }
  return true;
}

// A split profile: exponent p, crosstalk c, rim softness e.
std::shared_ptr<const DPPsfModel> SplitProfile(double p, double c, double e) {
  SplitProfileParams params;
  params.split_exponent = p;
  params.crosstalk = c;
  params.rim_softness = e;
  return std::make_shared<const SplitProfilePsf>(params);
}

// Measured kernel pairs at 10 px of an elliptical aperture with a soft
// split along a rotated axis, or of a cat-eye with a rim (SoftSplitKernels).
std::shared_ptr<const DPPsfModel> MeasuredKernels(double aspect,
                                                  double rotation_deg,
                                                  double strength,
                                                  double cut,
                                                  double rim) {
  const test::KernelPair k =
      test::SoftSplitKernels(10, aspect, rotation_deg, strength, cut, rim);
  return std::make_shared<const MeasuredKernelPsf>(k.left, k.right, 10, true);
}

// The simulated sensors: the model, split profiles, and measured kernels
// outside every family the estimator fits (an elliptical aperture 0.7 as
// tall as wide with a soft sigmoid split along an axis rotated by 20
// degrees, and a cat-eye, a disk cut by a second, offset disk, with a bright
// rim and a strong split).
std::vector<Sensor> MakeSensors() {
  return {
      {"translating disk (the model)",
       std::make_shared<const TranslatingDiskPsf>(),
       nullptr},
      {"sharp split (p 0.3)", SplitProfile(0.3, 0, 0), nullptr},
      {"soft split (p 2.5)", SplitProfile(2.5, 0, 0), nullptr},
      {"crosstalk 0.12", SplitProfile(1, 0.12, 0), nullptr},
      {"soft rim 0.2 + split p 0.6", SplitProfile(0.6, 0, 0.2), nullptr},
      {"split varying across the frame (p 0.4 -> 1.5)",
       SplitProfile(0.4, 0, 0),
       SplitProfile(1.5, 0, 0)},
      {"elliptical aperture, rotated soft split (kernels)",
       MeasuredKernels(0.7, 20, 2.5, 0, 0),
       nullptr},
      {"cat-eye, bright rim, strong split (kernels)",
       MeasuredKernels(1.0, 0, 8, 0.35, 2),
       nullptr},
      {"kernels changing across the frame (ellipse, weak -> cat-eye, strong)",
       MeasuredKernels(0.7, 15, 1.2, 0, 0),
       MeasuredKernels(1.0, 0, 6, 0.3, 1)},
      // Apodized: light falling to a tenth towards the rim (1 - 0.9 rho^4),
      // the family's bright rim reversed, with a soft split.
      {"apodized, soft split (kernels)",
       MeasuredKernels(1.0, 0, 1.5, 0, -0.9),
       nullptr},
  };
}

// The run's sizes and the table's header.
void PrintHeader(const BenchArguments& args) {
  std::printf(
      "psf_profile_bench: %d scenes x %d views of %dx%d, noise %.3f\n"
      "r_s = s_est / s_true; e_s = mean |1 - r_s|\n\n",
      args.num_scenes,
      args.num_views,
      kWidth,
      kHeight,
      args.noise);
  std::printf(
      "| true profile | translating_disk r_s | auto r_s | calibrated r_s | "
      "calibrated shape r_s | e_s translating_disk | e_s auto | e_s "
      "calibrated | e_s calibrated shape |\n|---|---|---|---|---|---|---|---|"
      "---|\n");
}

// One scene's estimates in every mode, in the table's order (an empty Run
// where the calibration gave no profile).
std::array<Run, kModes> EstimateModes(const std::vector<DPView>& views,
                                      const Calibrated& calibrated,
                                      double scale) {
  const DPPsfField disk =
      DPPsfField::Uniform(std::make_shared<const TranslatingDiskPsf>());
  return {
      Estimate(views, disk, false, scale),
      Estimate(views, disk, true, scale),
      calibrated.family.cells.empty() ? Run()
                                      : Estimate(views,
                                                 calibrated.family,
                                                 false,
                                                 scale,
                                                 calibrated.family_uncertainty),
      calibrated.shape.cells.empty() ? Run()
                                     : Estimate(views,
                                                calibrated.shape,
                                                false,
                                                scale,
                                                calibrated.shape_uncertainty)};
}

// Adds one scene's estimates to the row's cells and errors and to the
// totals' runtimes and interval counts.
void AddScene(const std::array<Run, kModes>& runs,
              int scene,
              Row* row,
              Totals* totals) {
  totals->time_disk += runs[0].seconds;
  totals->time_auto += runs[1].seconds;
  for (int m = 0; m < kModes; ++m) {
    char cell[32];
    if (runs[m].success) {
      std::snprintf(cell,
                    sizeof(cell),
                    "%.3f%s",
                    runs[m].ratio,
                    runs[m].holds ? "" : " (misses)");
      row->errors[m] += std::abs(1 - runs[m].ratio);
      ++row->counts[m];
      ++totals->answered[m];
      totals->held[m] += runs[m].holds ? 1 : 0;
    } else {
      std::snprintf(cell, sizeof(cell), "refused");
    }
    row->cells[m] += (scene ? ", " : "") + std::string(cell);
  }
}

// The sensor's row: r_s per mode, then e_s per mode ("-" without answers).
void PrintRow(const Sensor& sensor, const Row& row) {
  std::printf("| %s | %s | %s | %s | %s |",
              sensor.name.c_str(),
              row.cells[0].c_str(),
              row.cells[1].c_str(),
              row.cells[2].c_str(),
              row.cells[3].c_str());
  for (int m = 0; m < kModes; ++m) {
    if (row.counts[m] > 0) {
      std::printf(" %.3f |", row.errors[m] / row.counts[m]);
    } else {
      std::printf(" - |");
    }
  }
  std::printf("\n");
  std::fflush(stdout);
}

// Calibrates for the sensor, estimates every scene in every mode and prints
// the sensor's row.
void BenchSensor(const Sensor& sensor,
                 const BenchArguments& args,
                 Totals* totals) {
  const Calibrated calibrated = Calibrate(sensor, args.noise);
  totals->calibration_notes.push_back(sensor.name + ": " + calibrated.note);
  Row row;
  for (int scene = 0; scene < args.num_scenes; ++scene) {
    const double scale = 0.05 + 0.03 * scene;
    std::vector<DPView> views;
    for (int v = 0; v < args.num_views; ++v) {
      views.push_back(Capture(sensor, scene, v, scale, args.noise));
    }
    const std::array<Run, kModes> runs =
        EstimateModes(views, calibrated, scale);
    AddScene(runs, scene, &row, totals);
    if (scene == 0) totals->notes.push_back(sensor.name + ": " + runs[1].note);
  }
  if (calibrated.family.cells.empty()) row.cells[2] = "calibration refused";
  if (calibrated.shape.cells.empty()) row.cells[3] = "shape not measured";
  PrintRow(sensor, row);
}

// The runtimes, the intervals holding the truth, and the notes of `auto`
// and of the calibrations.
void PrintSummary(const Totals& totals) {
  std::printf(
      "\nruntime (all scenes): translating_disk %.1f s, auto %.1f s (x %.2f)\n",
      totals.time_disk,
      totals.time_auto,
      totals.time_auto / totals.time_disk);
  std::printf(
      "\nintervals holding the truth: translating_disk %d of %d, auto %d of "
      "%d, calibrated %d of %d, calibrated shape %d of %d answers\n",
      totals.held[0],
      totals.answered[0],
      totals.held[1],
      totals.answered[1],
      totals.held[2],
      totals.answered[2],
      totals.held[3],
      totals.answered[3]);
  std::printf("\nauto, first scene of each profile:\n");
  for (const std::string& note : totals.notes) {
    std::printf("- %s\n", note.c_str());
  }
  std::printf("\ncalibration (focus fitted):\n");
  for (const std::string& note : totals.calibration_notes) {
    std::printf("- %s\n", note.c_str());
  }
}

}  // namespace

int main(int argc, char** argv) {
  BenchArguments args;
  if (!ParseArguments(argc, argv, &args)) return 1;
  const std::vector<Sensor> sensors = MakeSensors();
  PrintHeader(args);
  Totals totals;
  for (const Sensor& sensor : sensors) {
    if (!args.only.empty() &&
        sensor.name.find(args.only) == std::string::npos) {
      continue;
    }
    BenchSensor(sensor, args, &totals);
  }
  PrintSummary(totals);
  return 0;
}
