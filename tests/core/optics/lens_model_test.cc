#include "dpsfm/core/optics/lens_model.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace dpsfm {
namespace {

DPLensData Canon50() {
  DPLensData lens;
  lens.focal_length_mm = 50;
  lens.f_number = 1.8;
  lens.pixel_pitch_um = 5.36;
  return lens;
}

TEST(LensModel, CheckRejectsMissingData) {
  EXPECT_TRUE(Canon50().Check());
  DPLensData lens = Canon50();
  lens.f_number = 0;
  EXPECT_FALSE(lens.Check());
  lens = Canon50();
  lens.pixel_pitch_um = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(lens.Check());
}

TEST(LensModel, BlurSignAndClosedForm) {
  const DPLensData lens = Canon50();
  const double g = 1500;  // mm
  EXPECT_DOUBLE_EQ(SignedBlurDiameterMm(lens, g, g), 0.0);
  EXPECT_GT(SignedBlurDiameterMm(lens, g, 3000), 0);  // farther: b > 0
  EXPECT_LT(SignedBlurDiameterMm(lens, g, 1000), 0);  // nearer: b < 0
  // By hand: aperture L = f / N = 50 / 1.8 = 27.778 mm; the blur circle on
  // the sensor is b = L f (z - g) / (z (g - f)) = 27.778 * 50 * 1500 /
  // (3000 * 1450) = 0.478927 mm for g = 1.5 m, z = 3 m.
  EXPECT_NEAR(SignedBlurDiameterMm(lens, g, 3000), 0.4789272030651341, 1e-12);
  // Far limit: b -> L f / (g - f) = 1388.89 / 1450 = 0.957854 mm.
  EXPECT_NEAR(SignedBlurDiameterMm(lens, g, 1e15), 0.9578544061302682, 1e-11);
  // Focus at infinity: b = -L f / z = -1388.89 / 2000 = -0.694444 mm.
  EXPECT_NEAR(
      SignedBlurDiameterMm(lens, std::numeric_limits<double>::infinity(), 2000),
      -0.6944444444444444,
      1e-12);
}

TEST(LensModel, RadiusInPixels) {
  // 10 um diameter on 5 um pixels: radius 1 px.
  EXPECT_DOUBLE_EQ(BlurRadiusPxFromDiameterMm(0.010, 0.005), 1.0);
  EXPECT_DOUBLE_EQ(BlurDiameterMmFromRadiusPx(1.0, 0.005), 0.010);
}

// Forward (s, g', z') -> r and back: the linear row (the estimator's way
// from blur back to the unknowns) is satisfied exactly by the true ones.
TEST(LensModel, ForwardAndBack) {
  const DPLensData lens = Canon50();
  const double pitch_mm = 2 * lens.PixelPitchMm();  // frame resized by 0.5
  for (double scale : {0.01, 0.37, 1.0, 4.2}) {
    for (double g_model : {0.8 / scale, 2.0 / scale}) {
      for (double z_model : {0.5 / scale, 1.7 / scale, 30.0 / scale}) {
        const double r =
            PredictBlurRadiusPx(lens, pitch_mm, scale, g_model, z_model);
        const double mm = ModelUnitMm(scale);
        const LinearRow row = MakeLinearRow(lens, pitch_mm, r, z_model);
        const double gbar = 1.0 / (mm * g_model);
        const double sbar = 1.0 / mm;
        EXPECT_NEAR(row.gamma * gbar + row.minus_l * sbar,
                    row.rhs,
                    1e-9 * (1 + std::abs(row.rhs)));
        EXPECT_NEAR(row.rhs, r, 1e-12 * (1 + std::abs(r)));
        EXPECT_NEAR(ScaleFromSbar(sbar), scale, 1e-12 * scale);
        EXPECT_NEAR(
            FocusModelFromUnknowns(gbar, sbar), g_model, 1e-9 * g_model);
      }
    }
  }
}

TEST(LensModel, PhoneNumbers) {
  // Pixel 4 DP: f = 4.38 mm, N = 1.73, pitch 2.8 um, focus 0.5 m, object at
  // 0.25 m. By hand: L = 2.5318 mm, b = L f (z - g) / (z (g - f)) =
  // 11.089 * (-250) / (250 * 495.62) = -0.022374 mm, radius b / 2 over the
  // pitch = -0.011187 / 0.0028 = -3.995 px.
  DPLensData lens;
  lens.focal_length_mm = 4.38;
  lens.f_number = 1.73;
  lens.pixel_pitch_um = 2.8;
  const double r =
      PredictBlurRadiusPx(lens, lens.PixelPitchMm(), 1.0, 0.5, 0.25);
  EXPECT_NEAR(r, -3.9954460196007364, 1e-9);
}

TEST(LensModel, RowRejectsNonPositiveDepth) {
  EXPECT_THROW(MakeLinearRow(Canon50(), 0.005, 1.0, 0.0),
               std::invalid_argument);
}

// Sensor-plane distances into object distances, against the closed form of
// u + v = D, 1/u + 1/v = 1/f: for f = 50 mm, D = 1000 mm the lens sits
// v = 1000 - 947.2136 = 52.7864 mm from the sensor (1/947.2136 + 1/52.7864
// = 1/50), so a target 800 mm from the sensor is 747.2136 mm from the lens.
TEST(LensModel, SensorDistancesToObjectDistances) {
  const double u = FocusObjectDistanceMm(1000, 50);
  EXPECT_NEAR(u, 500 + std::sqrt(200000.0), 1e-9);
  EXPECT_NEAR(1 / u + 1 / (1000 - u), 1.0 / 50, 1e-12);
  EXPECT_NEAR(
      ObjectDistanceFromSensorMm(800, 1000, 50), 800 - (1000 - u), 1e-9);
  EXPECT_NEAR(SensorDistanceOfFocusMm(u, 50), 1000, 1e-9);
  // At D = 4 f the lens is at 2 f from both; nearer it cannot focus.
  EXPECT_NEAR(FocusObjectDistanceMm(200, 50), 100, 1e-9);
  EXPECT_THROW(FocusObjectDistanceMm(199, 50), std::invalid_argument);
  // The example: taking the sensor distance for the object
  // distance (50 mm, focus 1.00 m, target 0.80 m) reads the radius ~12 %
  // small against the thin lens.
  DPLensData lens;
  lens.focal_length_mm = 50;
  lens.f_number = 2;
  lens.pixel_pitch_um = 5;
  const double wrong = SignedBlurDiameterMm(lens, 1000, 800);
  const double right =
      SignedBlurDiameterMm(lens, u, ObjectDistanceFromSensorMm(800, 1000, 50));
  EXPECT_NEAR(wrong / right, 0.88, 0.02);
}

}  // namespace
}  // namespace dpsfm
