// Without Exiv2 (-DDPSFM_WITH_EXIV2=OFF): no file's metadata is read, and
// every file says why, so that the run's lens notes tell the user once that
// lens data must come from lens.csv or the flags (README, "Licence").
#include "dpsfm/colmap/io/image_metadata_reader.h"

namespace dpsfm {
namespace internal {
namespace {

CameraMetadata NotRead() {
  CameraMetadata m;
  m.error =
      "this dp-sfm is built without Exiv2 (-DDPSFM_WITH_EXIV2=OFF), which "
      "reads the cameras' metadata";
  return m;
}

}  // namespace

CameraMetadata ReadMetadataFile(const std::string&) { return NotRead(); }

CameraMetadata ParseMetadataBytes(const std::string&) { return NotRead(); }

DeclaredEncoding ExifEncoding(const std::string&) { return {}; }

DeclaredEncoding ExifBlockEncoding(const std::string&) { return {}; }

}  // namespace internal
}  // namespace dpsfm
