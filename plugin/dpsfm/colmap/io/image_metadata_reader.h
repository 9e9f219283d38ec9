// The reader behind image_metadata.h's functions: Exiv2's
// (image_metadata_exiv2.cc) when dp-sfm is built with it
// (-DDPSFM_WITH_EXIV2=ON, the default), else one that reads nothing
// (image_metadata_none.cc). image_metadata.cc keeps what needs neither.
#pragma once

#include <string>

#include "dpsfm/colmap/io/image_metadata.h"

namespace dpsfm {
namespace internal {

// The metadata of an existing file, and of a whole file's bytes; `error`
// set where they cannot be read (for every file, without a reader).
CameraMetadata ReadMetadataFile(const std::string& path);
CameraMetadata ParseMetadataBytes(const std::string& file_bytes);

// EXIF ColorSpace = 1 (sRGB) in an image file's bytes, and in a bare TIFF
// structure (a PNG's eXIf chunk); kAuto where it is not said or cannot be
// read.
DeclaredEncoding ExifEncoding(const std::string& file_bytes);
DeclaredEncoding ExifBlockEncoding(const std::string& tiff);

}  // namespace internal
}  // namespace dpsfm
