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

#include "dpsfm/core/optics/encoding.h"

namespace dpsfm {

struct ExifLens {
  double focal_length_mm = 0;  // FocalLength, an exact rational
  double f_number = 0;         // FNumber
  std::string camera;          // "Make / Model", empty if absent
  std::string lens;            // LensModel
  // The recorded focus distance in mm, 0 if none: the middle of Canon's
  // maker-note window FocusDistanceLower/Upper (ShotInfo 19/20, cm) when
  // both are finite and within a factor 3, else EXIF SubjectDistance (m).
  double focus_distance_mm = 0;
  // The window's relative half-width, (upper - lower) / (upper + lower);
  // 0 for a single distance.
  double focus_bracket = 0;
  std::string focus_source;  // "Canon maker note", "SubjectDistance"
};

// Reads JPEG (APP1 "Exif"), TIFF-based files (TIFF, DNG, CR2, NEF, ...) and
// PNG (eXIf chunk). Zeros and empty strings where a tag is absent, the file
// is missing or not one of these formats.
ExifLens ReadExifLens(const std::string& path);

// The same on bytes already in memory (a whole file), for tests.
ExifLens ParseExifLens(const std::string& file_bytes);

// What a file itself says about how its values encode light: a PNG's sRGB
// or iCCP chunk (sRGB; an ICC profile whose name says "linear": linear), its
// gAMA chunk (1.0: linear; 1/2.2: sRGB), or EXIF ColorSpace = 1 (sRGB) in
// JPEG, TIFF or a PNG's eXIf chunk. kAuto with empty evidence when it says
// nothing.
struct DeclaredEncoding {
  DPEncoding encoding = DPEncoding::kAuto;
  std::string evidence;  // e.g. "PNG gAMA 1.0", "EXIF ColorSpace sRGB"
};
// On a whole file's bytes (DP frames are read once, colmap/io/dp_images.h).
DeclaredEncoding ParseDeclaredEncoding(const std::string& file_bytes);

}  // namespace dpsfm
