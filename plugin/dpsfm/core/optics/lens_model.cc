#include "dpsfm/core/optics/lens_model.h"

#include <cmath>
#include <sstream>

#include "dpsfm/core/util/check.h"

namespace dpsfm {

bool DPLensData::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_VALUE(
      std::isfinite(focal_length_mm) && focal_length_mm > 0, focal_length_mm);
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(f_number) && f_number > 0, f_number);
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(pixel_pitch_um) && pixel_pitch_um > 0,
                           pixel_pitch_um);
  return true;
}

std::string DPLensData::ToString() const {
  std::ostringstream s;
  s << "f=" << focal_length_mm << " mm, N=" << f_number
    << ", pitch=" << pixel_pitch_um << " um";
  return s.str();
}

double SignedBlurDiameterMm(const DPLensData& lens,
                            double focus_distance_mm,
                            double depth_mm) {
  // Eq. (focas_distance_ambiguity). Written with inverse distances so that
  // focus at infinity (1/g = 0) needs no special case.
  const double f = lens.focal_length_mm;
  const double inv_g = 1.0 / focus_distance_mm;
  const double inv_z = 1.0 / depth_mm;
  return lens.ApertureDiameterMm() * f / (1.0 - f * inv_g) * (inv_g - inv_z);
}

double FocusObjectDistanceMm(double sensor_to_focus_mm,
                             double focal_length_mm) {
  const double d = sensor_to_focus_mm, f = focal_length_mm;
  DPSFM_CHECK(f > 0 && d >= 4 * f && std::isfinite(d))
      << "a lens of " << f << " mm cannot focus at " << d
      << " mm from the sensor (needs at least 4 f)";
  return 0.5 * (d + std::sqrt(d * d - 4 * d * f));
}

double ObjectDistanceFromSensorMm(double sensor_to_point_mm,
                                  double sensor_to_focus_mm,
                                  double focal_length_mm) {
  const double u = FocusObjectDistanceMm(sensor_to_focus_mm, focal_length_mm);
  return sensor_to_point_mm - (sensor_to_focus_mm - u);
}

double SensorDistanceOfFocusMm(double focus_object_distance_mm,
                               double focal_length_mm) {
  const double u = focus_object_distance_mm, f = focal_length_mm;
  DPSFM_CHECK(u > f) << "focus object distance " << u
                     << " mm must exceed the focal length " << f << " mm";
  return u + f * u / (u - f);
}

double PredictBlurRadiusPx(const DPLensData& lens,
                           double pixel_pitch_mm,
                           double scale,
                           double focus_distance_model,
                           double depth_model) {
  const double mm = ModelUnitMm(scale);
  return BlurRadiusPxFromDiameterMm(
      SignedBlurDiameterMm(lens, mm * focus_distance_model, mm * depth_model),
      pixel_pitch_mm);
}

LinearRow MakeLinearRow(const DPLensData& lens,
                        double pixel_pitch_mm,
                        double radius_px,
                        double depth_model) {
  DPSFM_CHECK(depth_model > 0) << "depth must be positive, got " << depth_model;
  const double f = lens.focal_length_mm;
  const double l = lens.ApertureDiameterMm();
  const double b = BlurDiameterMmFromRadiusPx(radius_px, pixel_pitch_mm);
  // Eq. (one_pixel): b z'/f = z' (b + L) gbar - L sbar, then divided by
  // 2 p z' / f (see header).
  const double norm = f / (2.0 * pixel_pitch_mm * depth_model);
  LinearRow row;
  row.gamma = depth_model * (b + l) * norm;
  row.minus_l = -l * norm;
  row.rhs = b * depth_model / f * norm;
  return row;
}

}  // namespace dpsfm
