// Thin-lens defocus model that ties DP blur to scale-ambiguous depth.
//
// Units: every length inside the lens formula is in millimetres (focal
// length, aperture, blur diameter, focus distance, depth). Pixel pitch is
// given in micrometres as cameras quote it. Reconstruction ("model") units
// enter only through the scale s: metric metres = s * model units, so a model
// depth z' is z = 1000 * s * z' millimetres.
#pragma once

#include <limits>
#include <string>

namespace dpsfm {

// Per-view lens data. Every view carries its own, so multi-camera and
// multi-aperture captures need no special handling.
struct DPLensData {
  // Focal length f in mm.
  double focal_length_mm = 0;
  // f-number N; the aperture diameter is L = f / N.
  double f_number = 0;
  // Pitch of the DP frame's pixels as given to the core (before any internal
  // resize), in micrometres.
  double pixel_pitch_um = 0;
  // The focus distance the camera or the user recorded, from the
  // focal-plane mark (sensor plane), in mm; NaN = not recorded. Evidence
  // only: the estimate checks itself against it (ScaleCuesResult::
  // focus_check), it never replaces the fitted focus.
  double recorded_focus_mm = std::numeric_limits<double>::quiet_NaN();
  // The relative half-width of the window the record itself gives (Canon's
  // maker note records a focus bracket [lower, upper]: (upper - lower) /
  // (upper + lower) around its middle, recorded_focus_mm); 0 or NaN for a
  // single distance.
  double recorded_focus_bracket = 0;

  bool Check(std::string* failure = nullptr) const;
  double ApertureDiameterMm() const { return focal_length_mm / f_number; }
  double PixelPitchMm() const { return pixel_pitch_um * 1e-3; }
  std::string ToString() const;
};

// Millimetres per model unit for a scale s in metres per model unit.
inline double ModelUnitMm(double scale) { return 1000.0 * scale; }

// Eq. (focas_distance_ambiguity): signed circle-of-confusion diameter on the
// sensor in mm, b = L f / (1 - f/g) * (1/g - 1/z); b > 0 farther than the focal
// plane, b < 0 nearer. g and z in mm; g = +inf (focus at infinity) is allowed.
double SignedBlurDiameterMm(const DPLensData& lens,
                            double focus_distance_mm,
                            double depth_mm);

// r = b / (2 p): signed blur radius in pixels of pitch `pixel_pitch_mm`.
// (The paper prints r = p/2 * b; the dimensionally right form is b / (2p).)
inline double BlurRadiusPxFromDiameterMm(double b_mm, double pixel_pitch_mm) {
  return b_mm / (2.0 * pixel_pitch_mm);
}
inline double BlurDiameterMmFromRadiusPx(double r_px, double pixel_pitch_mm) {
  return 2.0 * r_px * pixel_pitch_mm;
}

// Distances measured from the camera's focal-plane mark (the sensor) into
// the thin lens's object distances (from the lens). A lens focused at
// sensor distance D_g sits at v = D_g - u_g from the sensor, with u_g the
// root of u^2 - D_g u + D_g f = 0 nearer D_g (1/u + 1/v = 1/f, u + v = D_g);
// any other point at sensor distance D lies at D - v from the lens. Throws
// std::invalid_argument when D_g < 4 f (no real focus: closer than the
// lens can focus).
double FocusObjectDistanceMm(double sensor_to_focus_mm, double focal_length_mm);
double ObjectDistanceFromSensorMm(double sensor_to_point_mm,
                                  double sensor_to_focus_mm,
                                  double focal_length_mm);
// The inverse of FocusObjectDistanceMm: u + f u / (u - f).
double SensorDistanceOfFocusMm(double focus_object_distance_mm,
                               double focal_length_mm);

// Eq. (solution01) in pixels: blur radius of a point at model depth z' seen by
// a view with model focus distance g' under scale s (metres per model unit).
// `pixel_pitch_mm` is the pitch of the pixels r is measured in (it differs
// from lens.PixelPitchMm() when the frame was resized).
double PredictBlurRadiusPx(const DPLensData& lens,
                           double pixel_pitch_mm,
                           double scale,
                           double focus_distance_model,
                           double depth_model);

// One row of eq. (linear_system), from eq. (one_pixel):
//   b z' / f = z' (b + L) gbar - L sbar,    gbar = 1/g [1/mm],
//                                           sbar = 1/(1000 s) [model unit/mm].
// The row is divided by (2 p z' / f) so that its residual reads in pixels of
// blur radius (the rhs becomes r itself); that makes rows from views with
// different lenses, pitches and depths comparable inside one L1 fit, and
// leaves the solution of an exact system unchanged.
struct LinearRow {
  double gamma = 0;    // coefficient of gbar_i (normalised gamma_ij)
  double minus_l = 0;  // coefficient of sbar (normalised -L_i)
  double rhs = 0;      // normalised b_ij z'_ij / f_i  (= r_ij in px)
};
LinearRow MakeLinearRow(const DPLensData& lens,
                        double pixel_pitch_mm,
                        double radius_px,
                        double depth_model);

// Converts the linear unknowns back: s = 1 / (1000 sbar), g' = sbar / gbar.
inline double ScaleFromSbar(double sbar) { return 1.0 / (1000.0 * sbar); }
inline double FocusModelFromUnknowns(double gbar, double sbar) {
  return sbar / gbar;
}

}  // namespace dpsfm
