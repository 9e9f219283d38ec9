// Per-image lens data (focal length, f-number, pixel pitch) with the
// contract's precedence: lens.csv row > explicit flag > EXIF of the original
// image > derived (pitch only, f_mm / f_px of the calibrated camera). The
// recorded focus distance: lens.csv > EXIF (Canon maker note, then
// SubjectDistance).
#pragma once

#include <map>
#include <string>

#include "dpsfm/colmap/exif.h"
#include "dpsfm/core/lens_model.h"

namespace dpsfm {

// One row of lens.csv; zero means "empty cell".
struct LensCsvRow {
  double focal_length_mm = 0;
  double f_number = 0;
  double pixel_pitch_um = 0;
  double focus_distance_m = 0;  // recorded, from the focal-plane mark
  std::string camera, lens;     // for the DP profile library
};

// Reads lens.csv (header `name,focal_length_mm,f_number,pixel_pitch_um`,
// optionally followed by any of `focus_distance_m` (the recorded focus
// distance from the camera's focal-plane mark), `camera` and `lens` (the
// DP profile library's keys, as EXIF Make / Model and LensModel); empty
// cells are allowed after f_number). Throws InputError naming the file and
// line.
std::map<std::string, LensCsvRow> ReadLensCsv(const std::string& path);

// Lens data of one image and where each number came from ("lens.csv",
// "flag", "EXIF", "derived"), for the log and the report.
struct ResolvedLens {
  DPLensData lens;  // pitch is of the MODEL camera's pixels
  std::string focal_length_source;
  std::string f_number_source;
  std::string pixel_pitch_source;
  // Where DPLensData::recorded_focus_mm came from ("lens.csv", "EXIF
  // Canon maker note", "EXIF SubjectDistance"), empty if none.
  std::string focus_source;
  // The DP profile library's keys (lens.csv > EXIF; empty if unknown).
  std::string camera, lens_model;
};

struct LensFlags {
  double focal_length_mm = 0;
  double f_number = 0;
  double pixel_pitch_um = 0;
};

// Applies the precedence for one image. `exif` may be null (no original
// image); `camera_focal_px` is the calibrated focal length in pixels (used to
// derive the pitch). Throws InputError naming the image and the three ways
// to supply a missing focal length or f-number.
ResolvedLens ResolveLens(const std::string& image_name,
                         const std::map<std::string, LensCsvRow>& csv,
                         const LensFlags& flags,
                         const ExifLens* exif,
                         double camera_focal_px);

}  // namespace dpsfm
