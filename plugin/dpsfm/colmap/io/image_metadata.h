// What an image file says about itself: the camera, lens and focus it was
// taken with (EXIF and maker notes, read by Exiv2), and how its values
// encode light.
//
// Exiv2 reads every format the cameras this product is for write: JPEG,
// TIFF, PNG, the TIFF-based raws (CR2, DNG, NEF, ARW, ...), and CR3 and
// HEIF/HIF (ISO base media files, which Exiv2 0.27 reads once BMFF support
// is switched on at run time). It decodes Canon's maker notes, where a
// Canon body records the lens's focus-distance window. Neither COLMAP 3
// (FreeImage) nor COLMAP 4 (OpenImageIO) exposes those.
//
// Built with -DDPSFM_WITH_EXIV2=OFF (README, "Licence"), no file's camera
// metadata is read: each comes back with `error` saying so, and only a
// PNG's own chunks declare its encoding (image_metadata_reader.h).
//
// Nothing here throws or logs: a file whose metadata cannot be read comes
// back with `error` set (one line, in this product's words; Exiv2's own
// messages are muted).
#pragma once

#include <string>

#include "dpsfm/core/optics/encoding.h"

namespace dpsfm {

// One number read from a file, and the tag (Exiv2's key) it came from.
struct MetadataNumber {
  double value = 0;  // 0: not recorded
  std::string tag;   // e.g. "Exif.Photo.FNumber"
  bool recorded() const { return value > 0; }
};

// The focus distance a camera recorded. Canon bodies record the window the
// lens's focus encoder reports, in centimetres: FocusDistanceUpper and
// FocusDistanceLower, in FileInfo (tag 0x0093, entries 20 and 21) on
// R-series bodies and in ShotInfo (tag 0x0004, entries 19 and 20) on older
// ones. EXIF's SubjectDistance is one distance in metres; so are the
// distances Exiv2 decodes from other makers' notes (Nikon's lens data).
struct RecordedFocus {
  double distance_mm = 0;  // 0: none; the window's middle for a window
  // The window's relative half-width, (upper - lower) / (upper + lower);
  // 0 for a single distance.
  double bracket = 0;
  std::string tag;  // where it came from, e.g. "Exif.CanonFi.FocusDistanceUpper/Lower"
  double lower_mm = 0, upper_mm = 0;  // the window, when one was recorded
};

struct CameraMetadata {
  std::string make;        // Exif.Image.Make, trimmed
  std::string model;       // Exif.Image.Model
  std::string lens_model;  // Exif.Photo.LensModel, else Canon's LensModel
  MetadataNumber focal_length_mm;  // Exif.Photo.FocalLength
  MetadataNumber f_number;         // Exif.Photo.FNumber
  // The sensor's pixel pitch, from FocalPlaneXResolution and its unit: the
  // pitch of the camera's full-resolution image (a model built from resized
  // images has other pixels; the lens data check says so).
  MetadataNumber pixel_pitch_um;
  RecordedFocus focus;
  // A focus tag that the file holds but that gives no distance, and why
  // ("Exif.CanonFi.FocusDistanceUpper is infinity: an open window"); empty
  // when there is none or a distance was read.
  std::string focus_note;
  // Why the file's metadata could not be read at all, in one line; empty
  // when it was read (a file with no EXIF is read, with nothing in it).
  std::string error;

  // "Make / Model" (the DP profile library's camera key), empty if neither.
  std::string Camera() const;
  bool Empty() const;
};

// The metadata of the file at `path`. A missing or unreadable file, or one
// of no format Exiv2 knows, comes back with `error` set.
CameraMetadata ReadCameraMetadata(const std::string& path);

// The same on a whole file's bytes (for files already in memory, and
// tests).
CameraMetadata ParseCameraMetadata(const std::string& file_bytes);

// What a file itself says about how its values encode light: a PNG's sRGB
// or iCCP chunk (sRGB; an ICC profile whose name says "linear": linear), its
// gAMA chunk (1.0: linear; 1/2.2: sRGB), or EXIF ColorSpace = 1 (sRGB) in
// any format Exiv2 reads (a PNG's eXIf chunk included). kAuto with empty
// evidence when it says nothing.
struct DeclaredEncoding {
  DPEncoding encoding = DPEncoding::kAuto;
  std::string evidence;  // e.g. "PNG gAMA 1.0", "EXIF ColorSpace sRGB"
};
// On a whole file's bytes (DP frames are read once, colmap/io/dp_images.h).
DeclaredEncoding ParseDeclaredEncoding(const std::string& file_bytes);

}  // namespace dpsfm
