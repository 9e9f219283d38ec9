#include "dpsfm/core/calibration/target_calibration.h"

#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "dpsfm/core/calibration/target_solver.h"
#include "tests/core/synthetic_dp.h"

namespace dpsfm {
namespace {

// A sensor outside the split family: an elliptical aperture (0.75 as tall
// as wide) whose light divides between the views by a soft sigmoid along
// an axis rotated by 16 degrees, with a weaker split on the right half of
// the frame. Kernels given as measured pairs at 10 px (far side).
cv::Mat EllipseView(double strength, bool left_view) {
  const test::KernelPair k = test::SoftSplitKernels(
      10, 0.75, std::atan2(0.28, 0.96) * 180 / M_PI, strength);
  return left_view ? k.left : k.right;
}

struct Sensor {
  MeasuredKernelPsf left_half, right_half;
  Sensor()
      : left_half(EllipseView(3.0, true), EllipseView(3.0, false), 10, true),
        right_half(EllipseView(1.2, true), EllipseView(1.2, false), 10, true) {}
};

constexpr double kFocalMm = 50, kFNumber = 8, kPitchMm = 0.012;

DPLensData Lens() {
  DPLensData lens;
  lens.focal_length_mm = kFocalMm;
  lens.f_number = kFNumber;
  lens.pixel_pitch_um = kPitchMm * 1000;
  return lens;
}

// The true blur radius of a plane at `target_mm` from the sensor with the
// focus at `focus_mm` from the sensor, from the thin lens written out here
// (u + v = D, 1/u + 1/v = 1/f): independent of the code under test.
double TrueRadius(double target_mm, double focus_mm) {
  const double u_g =
      0.5 *
      (focus_mm + std::sqrt(focus_mm * focus_mm - 4 * focus_mm * kFocalMm));
  const double v = focus_mm - u_g;
  const double u_t = target_mm - v;
  // Image of the target at v_t; signed blur diameter L (v - v_t) / v_t
  // (> 0 farther than the focus).
  const double v_t = 1 / (1 / kFocalMm - 1 / u_t);
  const double b = kFocalMm / kFNumber * (v - v_t) / v_t;
  return b / (2 * kPitchMm);
}

CalibrationCapture Capture(const Sensor& sensor,
                           double target_mm,
                           double focus_mm,
                           int seed) {
  const cv::Size size(420, 280);
  const double r = TrueRadius(target_mm, focus_mm);
  test::TextureOptions texture;
  const cv::Mat sharp = test::MakeTexture(size, seed, texture);
  test::RenderOptions render;
  render.noise_sigma = 0.003;
  render.noise_seed = seed + 1;
  const test::DPPair a = test::RenderDP(sharp, sensor.left_half, r, render);
  const test::DPPair b = test::RenderDP(sharp, sensor.right_half, r, render);
  test::DPPair pair;
  pair.left = a.left.clone();
  pair.right = a.right.clone();
  // Right half of the frame: the weaker split.
  b.left.colRange(size.width / 2, size.width)
      .copyTo(pair.left.colRange(size.width / 2, size.width));
  b.right.colRange(size.width / 2, size.width)
      .copyTo(pair.right.colRange(size.width / 2, size.width));
  CalibrationCapture capture;
  capture.name = std::to_string(static_cast<int>(target_mm)) + " mm";
  capture.patches = ExtractProfilePatches(test::ToGray(pair.left),
                                          test::ToGray(pair.right),
                                          41,
                                          20,
                                          16,
                                          std::nan(""),
                                          1.5);
  capture.lens = Lens();
  capture.working_pitch_mm = kPitchMm;
  capture.target_distance_mm = target_mm;
  return capture;
}

TargetCalibrationOptions Options() {
  TargetCalibrationOptions options;
  options.blur.max_radius_px = 14;
  options.grid_rows = 1;
  options.grid_cols = 2;
  options.num_bootstrap = 60;
  return options;
}

}  // namespace

// Two planes, the focus unknown: the calibration finds the focus and each
// half's centroid offset (the kernels' own, integrated numerically).
TEST(CalibrateFromTargets, UnknownFocusAndAProfileOutsideTheFamily) {
  const Sensor sensor;
  const double focus = 1000;
  std::vector<CalibrationCapture> captures = {Capture(sensor, 700, focus, 10),
                                              Capture(sensor, 1700, focus, 20)};
  std::printf("true radii %.2f and %.2f px\n",
              TrueRadius(700, focus),
              TrueRadius(1700, focus));
  const TargetCalibration c = CalibrateFromTargets(captures, Options());
  std::printf("%s (%.1f s)\n", c.reason.c_str(), c.seconds);
  ASSERT_TRUE(c.determined) << c.reason;
  EXPECT_TRUE(c.focus_fitted);
  EXPECT_NEAR(c.focus_distance_mm / focus, 1.0, 0.03);
  EXPECT_LE(c.focus_ci_low_mm, focus * 1.005);
  EXPECT_GE(c.focus_ci_high_mm, focus * 0.995);
  const double left_truth = CentroidOffsetPerRadius(sensor.left_half, 6);
  const double right_truth = CentroidOffsetPerRadius(sensor.right_half, 6);
  std::printf("cells %.4f %.4f, truth %.4f %.4f\n",
              c.cell_centroid_offsets[0],
              c.cell_centroid_offsets[1],
              left_truth,
              right_truth);
  ASSERT_EQ(c.cell_centroid_offsets.size(), 2u);
  EXPECT_NEAR(c.cell_centroid_offsets[0] / left_truth, 1.0, 0.06);
  EXPECT_NEAR(c.cell_centroid_offsets[1] / right_truth, 1.0, 0.06);
}

// The focus given: it is used as is, and with it one capture suffices.
TEST(CalibrateFromTargets, KnownFocusOneCapture) {
  const Sensor sensor;
  std::vector<CalibrationCapture> captures = {Capture(sensor, 650, 1000, 30)};
  captures[0].focus_distance_mm = 1000;
  const TargetCalibration c = CalibrateFromTargets(captures, Options());
  std::printf("%s\n", c.reason.c_str());
  ASSERT_TRUE(c.determined) << c.reason;
  EXPECT_FALSE(c.focus_fitted);
  EXPECT_DOUBLE_EQ(c.focus_distance_mm, 1000);
  EXPECT_NEAR(c.capture_radius_px[0] / TrueRadius(650, 1000), 1.0, 1e-9);
}

// Refusals: the focus unknown with one capture, and a capture in focus.
TEST(CalibrateFromTargets, RefusesWhatTheCapturesDoNotDetermine) {
  const Sensor sensor;
  const TargetCalibration one =
      CalibrateFromTargets({Capture(sensor, 700, 1000, 40)}, Options());
  EXPECT_FALSE(one.determined);
  EXPECT_NE(one.reason.find("two or more"), std::string::npos) << one.reason;
  std::vector<CalibrationCapture> focused = {Capture(sensor, 1000, 1000, 50),
                                             Capture(sensor, 1010, 1000, 60)};
  const TargetCalibration sharp = CalibrateFromTargets(focused, Options());
  EXPECT_FALSE(sharp.determined);
}

// The predicted radius of a plane 600 mm from the sensor, focus 1000 mm,
// f = 50 mm at f/8, 12 um pixels, by hand (b = L f / (1 - f/g) (1/g - 1/z),
// r = b / (2 p)): from the thin lens focused there (u_g = 947.2136 mm, the
// lens 52.7864 mm from the sensor: -10.60831 px), and from an entrance
// pupil 40 mm in front of the sensor (g = 960, z = 560 mm: -10.22043 px).
TEST(PredictedRadiusPx, ThinLensOrEntrancePupil) {
  CalibrationCapture capture;
  capture.lens = Lens();
  capture.working_pitch_mm = kPitchMm;
  capture.target_distance_mm = 600;
  EXPECT_NEAR(PredictedRadiusPx(capture, 1000), -10.60831, 1e-4);
  EXPECT_NEAR(PredictedRadiusPx(capture, 1000), TrueRadius(600, 1000), 1e-9);
  capture.entrance_pupil_mm = 40;
  EXPECT_NEAR(PredictedRadiusPx(capture, 1000), -10.22043, 1e-4);
  // A focus within a focal length of the pupil has no real image.
  EXPECT_TRUE(std::isnan(PredictedRadiusPx(capture, 80)));
}

}  // namespace dpsfm
