// The few EXIF fields the estimator uses, read from the original image.
//
// Hand-written on purpose: COLMAP 3.x reads images with FreeImage and 4.x
// with OpenImageIO, neither exposes Canon's maker notes (where the focus
// distance of a Canon body is), and a plugin that builds against both cannot
// rely on either. The reader walks TIFF image file directories only (no
// pixels), bounds-checks every offset, and never throws: a file it cannot
// parse simply has no EXIF.
#pragma once

#include <string>

namespace dpsfm {

struct ExifLens {
  double focal_length_mm = 0;  // FocalLength, an exact rational
  double f_number = 0;         // FNumber
  std::string camera;          // "Make / Model", empty if absent
  std::string lens;            // LensModel
  // The recorded focus distance in mm, 0 if none: Canon's maker-note
  // FocusDistanceLower/Upper (ShotInfo 19/20, cm), their mean when both are
  // finite and within a factor 1.5, else EXIF SubjectDistance (m).
  double focus_distance_mm = 0;
  std::string focus_source;  // "Canon maker note", "SubjectDistance"
};

// Reads JPEG (APP1 "Exif"), TIFF-based files (TIFF, DNG, CR2, NEF, ...) and
// PNG (eXIf chunk). Zeros and empty strings where a tag is absent, the file
// is missing or not one of these formats.
ExifLens ReadExifLens(const std::string& path);

// The same on bytes already in memory (a whole file), for tests.
ExifLens ParseExifLens(const std::string& file_bytes);

}  // namespace dpsfm
