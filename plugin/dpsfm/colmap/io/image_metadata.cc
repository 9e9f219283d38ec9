#include "dpsfm/colmap/io/image_metadata.h"

#include <cstdint>
#include <filesystem>
#include <sstream>

#include "colmap/util/string.h"
#include "dpsfm/colmap/io/image_metadata_reader.h"

namespace dpsfm {
namespace {

uint32_t BigEndian32(const std::string& s, size_t at) {
  const auto* p = reinterpret_cast<const unsigned char*>(s.data() + at);
  return uint32_t{p[0]} << 24 | uint32_t{p[1]} << 16 | uint32_t{p[2]} << 8 |
         p[3];
}

// The PNG chunks before the pixels that name a transfer curve (Exiv2 reads
// a PNG's EXIF, not its sRGB, iCCP and gAMA chunks).
DeclaredEncoding PngDeclaredEncoding(const std::string& s) {
  size_t at = 8;
  while (at + 12 <= s.size()) {
    const uint32_t length = BigEndian32(s, at);
    if (length > s.size() - at - 12) break;
    const std::string type = s.substr(at + 4, 4);
    const std::string data = s.substr(at + 8, length);
    DeclaredEncoding declared;
    if (type == "sRGB") {
      declared.encoding = DPEncoding::kSrgb;
      declared.evidence = "PNG sRGB chunk";
      return declared;
    }
    if (type == "iCCP") {
      std::string name = data.substr(0, data.find('\0'));
      std::string lower = name;
      colmap::StringToLower(&lower);
      declared.encoding = lower.find("linear") != std::string::npos
                              ? DPEncoding::kLinear
                              : DPEncoding::kSrgb;
      declared.evidence = "PNG ICC profile '" + name + "'";
      return declared;
    }
    if (type == "gAMA" && length == 4) {
      // The file's gamma x 100000: 100000 is linear, 45455 is 1/2.2.
      const double gamma = BigEndian32(s, at + 8) / 100000.0;
      if (gamma > 0.9 && gamma < 1.1) {
        declared.encoding = DPEncoding::kLinear;
      } else if (gamma > 0.4 && gamma < 0.5) {
        declared.encoding = DPEncoding::kSrgb;
      }
      if (declared.encoding != DPEncoding::kAuto) {
        std::ostringstream evidence;
        evidence << "PNG gAMA " << gamma;
        declared.evidence = evidence.str();
        return declared;
      }
    }
    if (type == "eXIf") return internal::ExifBlockEncoding(data);
    if (type == "IDAT" || type == "IEND") break;
    at += 12 + static_cast<size_t>(length);
  }
  return DeclaredEncoding();
}

bool IsPng(const std::string& bytes) {
  return bytes.size() >= 8 && bytes.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0;
}

}  // namespace

std::string CameraMetadata::Camera() const {
  if (make.empty() && model.empty()) return "";
  return make + " / " + model;
}

bool CameraMetadata::Empty() const {
  return make.empty() && model.empty() && lens_model.empty() &&
         !focal_length_mm.recorded() && !f_number.recorded() &&
         !pixel_pitch_um.recorded() && !(focus.distance_mm > 0);
}

CameraMetadata ReadCameraMetadata(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    CameraMetadata m;
    m.error = "no such file";
    return m;
  }
  return internal::ReadMetadataFile(path);
}

CameraMetadata ParseCameraMetadata(const std::string& bytes) {
  return internal::ParseMetadataBytes(bytes);
}

DeclaredEncoding ParseDeclaredEncoding(const std::string& bytes) {
  if (IsPng(bytes)) return PngDeclaredEncoding(bytes);
  return internal::ExifEncoding(bytes);
}

}  // namespace dpsfm
