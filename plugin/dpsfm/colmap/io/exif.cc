#include "dpsfm/colmap/io/exif.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include "colmap/util/string.h"
#include "dpsfm/colmap/io/text.h"

namespace dpsfm {
namespace {

// EXIF lives in a file's first segments; raw files put it in IFD0's
// neighbourhood. Reading more would only cost time on 50 MB raw files.
constexpr std::streamsize kMaxBytes = 8 << 20;

enum Tag : uint16_t {
  kMake = 0x010F,
  kModel = 0x0110,
  kExifIfd = 0x8769,
  kFNumber = 0x829D,
  kSubjectDistance = 0x9206,
  kFocalLength = 0x920A,
  kMakerNote = 0x927C,
  kLensModel = 0xA434,
  kColorSpace = 0xA001,
  kCanonShotInfo = 0x0004,
};

enum Type : uint16_t {
  kAscii = 2,
  kShort = 3,
  kLong = 4,
  kRational = 5,
  kUndefined = 7,
  kSRational = 10,
  kIfd = 13,
};

int TypeSize(uint16_t type) {
  switch (type) {
    case 1:
    case 2:
    case 6:
    case 7:
      return 1;  // BYTE ASCII SBYTE UNDEF
    case 3:
    case 8:
      return 2;  // SHORT SSHORT
    case 4:
    case 9:
    case 11:
    case 13:
      return 4;  // LONG SLONG FLOAT IFD
    case 5:
    case 10:
    case 12:
      return 8;  // RATIONAL SRATIONAL DOUBLE
    default:
      return 0;
  }
}

// A TIFF structure (from its "II"/"MM" header on) inside a byte string.
class Tiff {
 public:
  explicit Tiff(const std::string& bytes) : data_(bytes) {}

  bool Valid() const {
    if (data_.size() < 8) return false;
    if (data_.compare(0, 2, "II") != 0 && data_.compare(0, 2, "MM") != 0) {
      return false;
    }
    return U16(2) == 42;
  }
  uint32_t FirstIfd() const { return U32(4); }

  struct Entry {
    uint16_t tag = 0, type = 0;
    uint32_t count = 0;
    size_t value_offset = 0;  // where the value's bytes start
    bool ok = false;
  };

  // The entry of `tag` in the directory at `ifd`, with its value's bytes in
  // range (ok false if absent or out of range).
  Entry Find(uint32_t ifd, uint16_t tag) const {
    Entry entry;
    if (!InRange(ifd, 2)) return entry;
    const uint16_t n = U16(ifd);
    for (uint16_t i = 0; i < n; ++i) {
      const size_t at = ifd + 2 + 12 * static_cast<size_t>(i);
      if (!InRange(at, 12)) return entry;
      if (U16(at) != tag) continue;
      entry.tag = tag;
      entry.type = U16(at + 2);
      entry.count = U32(at + 4);
      const uint64_t size =
          static_cast<uint64_t>(TypeSize(entry.type)) * entry.count;
      if (size == 0 || size > data_.size()) return entry;
      entry.value_offset = size <= 4 ? at + 8 : U32(at + 8);
      entry.ok = InRange(entry.value_offset, static_cast<size_t>(size));
      return entry;
    }
    return entry;
  }

  std::string Ascii(uint32_t ifd, uint16_t tag) const {
    const Entry e = Find(ifd, tag);
    if (!e.ok || e.type != kAscii) return "";
    std::string value = data_.substr(e.value_offset, e.count);
    value = value.substr(0, value.find('\0'));
    return Trim(value);
  }

  // A RATIONAL's num/den as given; den 0 gives 0.
  bool Rational(uint32_t ifd,
                uint16_t tag,
                uint32_t* num,
                uint32_t* den) const {
    const Entry e = Find(ifd, tag);
    if (!e.ok || (e.type != kRational && e.type != kSRational)) return false;
    *num = U32(e.value_offset);
    *den = U32(e.value_offset + 4);
    return true;
  }
  double PositiveRational(uint32_t ifd, uint16_t tag) const {
    const Entry e = Find(ifd, tag);
    if (!e.ok || (e.type != kRational && e.type != kSRational)) return 0;
    const uint32_t num = U32(e.value_offset), den = U32(e.value_offset + 4);
    if (e.type == kSRational &&
        (static_cast<int32_t>(num) <= 0 || static_cast<int32_t>(den) <= 0)) {
      return 0;
    }
    return den == 0 ? 0 : static_cast<double>(num) / den;
  }
  // A sub-directory pointer (LONG or IFD), 0 if absent.
  uint32_t Offset(uint32_t ifd, uint16_t tag) const {
    const Entry e = Find(ifd, tag);
    if (!e.ok || (e.type != kLong && e.type != kIfd)) return 0;
    return U32(e.value_offset);
  }

  uint16_t U16(size_t at) const {
    if (!InRange(at, 2)) return 0;
    const auto* p = reinterpret_cast<const unsigned char*>(data_.data() + at);
    return Big() ? static_cast<uint16_t>(p[0] << 8 | p[1])
                 : static_cast<uint16_t>(p[1] << 8 | p[0]);
  }
  uint32_t U32(size_t at) const {
    if (!InRange(at, 4)) return 0;
    const auto* p = reinterpret_cast<const unsigned char*>(data_.data() + at);
    return Big() ? (uint32_t{p[0]} << 24 | uint32_t{p[1]} << 16 |
                    uint32_t{p[2]} << 8 | p[3])
                 : (uint32_t{p[3]} << 24 | uint32_t{p[2]} << 16 |
                    uint32_t{p[1]} << 8 | p[0]);
  }
  bool InRange(size_t at, size_t size) const {
    return at <= data_.size() && size <= data_.size() - at;
  }

 private:
  bool Big() const { return data_[0] == 'M'; }
  const std::string& data_;
};

// Canon's ShotInfo holds the lens's focus-distance window, [19] upper and
// [20] lower, in cm, 65535 for infinity and 0 when unknown (the layout
// ExifTool and Exiv2 document). Canon maker notes are a plain IFD whose
// offsets count from the TIFF header, in the TIFF's byte order.
double CanonFocusDistanceMm(const Tiff& tiff,
                            uint32_t exif_ifd,
                            double* bracket) {
  const Tiff::Entry note = tiff.Find(exif_ifd, kMakerNote);
  if (!note.ok) return 0;
  const Tiff::Entry shot =
      tiff.Find(static_cast<uint32_t>(note.value_offset), kCanonShotInfo);
  if (!shot.ok || shot.type != kShort || shot.count <= 20) return 0;
  const double upper = tiff.U16(shot.value_offset + 2 * 19);
  const double lower = tiff.U16(shot.value_offset + 2 * 20);
  if (lower <= 0 || upper <= 0 || upper >= 65535 || lower >= 65535) return 0;
  // A window is a distance as uncertain as its half-width; one wider than
  // a factor 3 (a lens reporting coarse steps) says too little to use.
  if (upper < lower || upper > 3 * lower) return 0;
  *bracket = (upper - lower) / (upper + lower);
  return 10.0 * 0.5 * (upper + lower);
}

ExifLens ParseTiff(const std::string& bytes) {
  ExifLens exif;
  const Tiff tiff(bytes);
  if (!tiff.Valid()) return exif;
  const uint32_t ifd0 = tiff.FirstIfd();
  const std::string make = tiff.Ascii(ifd0, kMake);
  const std::string model = tiff.Ascii(ifd0, kModel);
  if (!make.empty() || !model.empty()) exif.camera = make + " / " + model;
  const uint32_t exif_ifd = tiff.Offset(ifd0, kExifIfd);
  if (exif_ifd == 0) return exif;
  exif.focal_length_mm = tiff.PositiveRational(exif_ifd, kFocalLength);
  exif.f_number = tiff.PositiveRational(exif_ifd, kFNumber);
  exif.lens = tiff.Ascii(exif_ifd, kLensModel);

  if (make.compare(0, 5, "Canon") == 0) {
    exif.focus_distance_mm =
        CanonFocusDistanceMm(tiff, exif_ifd, &exif.focus_bracket);
    if (exif.focus_distance_mm > 0) exif.focus_source = "Canon maker note";
  }
  if (exif.focus_distance_mm <= 0) {
    // SubjectDistance in m; 0 means unknown and 0xFFFFFFFF infinity.
    uint32_t num = 0, den = 0;
    if (tiff.Rational(exif_ifd, kSubjectDistance, &num, &den) && den != 0 &&
        num != 0 && num != 0xFFFFFFFFu) {
      exif.focus_distance_mm = 1000.0 * num / den;
      exif.focus_source = "SubjectDistance";
    }
  }
  return exif;
}

uint32_t BigEndian32(const std::string& s, size_t at) {
  const auto* p = reinterpret_cast<const unsigned char*>(s.data() + at);
  return uint32_t{p[0]} << 24 | uint32_t{p[1]} << 16 | uint32_t{p[2]} << 8 |
         p[3];
}

// The TIFF block of a JPEG's APP1 "Exif" segment, empty if none.
std::string JpegExif(const std::string& s) {
  size_t at = 2;
  while (at + 4 <= s.size()) {
    if (static_cast<unsigned char>(s[at]) != 0xFF) return "";
    const unsigned char marker = static_cast<unsigned char>(s[at + 1]);
    if (marker == 0xD8 || (marker >= 0xD0 && marker <= 0xD7) ||
        marker == 0x01) {
      at += 2;  // standalone markers
      continue;
    }
    if (marker == 0xDA || marker == 0xD9) return "";  // pixels begin
    const size_t length = static_cast<unsigned char>(s[at + 2]) << 8 |
                          static_cast<unsigned char>(s[at + 3]);
    if (length < 2 || at + 2 + length > s.size()) return "";
    if (marker == 0xE1 && length >= 8 &&
        s.compare(at + 4, 6, std::string("Exif\0\0", 6)) == 0) {
      return s.substr(at + 10, length - 8);
    }
    at += 2 + length;
  }
  return "";
}

// The TIFF block of a PNG's eXIf chunk, empty if none.
std::string PngExif(const std::string& s) {
  size_t at = 8;
  while (at + 12 <= s.size()) {
    const uint32_t length = BigEndian32(s, at);
    if (length > s.size() - at - 12) return "";
    const std::string type = s.substr(at + 4, 4);
    if (type == "eXIf") return s.substr(at + 8, length);
    if (type == "IEND") return "";
    at += 12 + static_cast<size_t>(length);
  }
  return "";
}

// The file's first kMaxBytes, empty if it cannot be read (no EXIF then).
std::string ReadHead(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return "";
  std::string bytes(static_cast<size_t>(kMaxBytes), '\0');
  file.read(&bytes[0], kMaxBytes);
  bytes.resize(static_cast<size_t>(file.gcount()));
  return bytes;
}

// EXIF ColorSpace (1 = sRGB) of a TIFF block, 0 if absent.
int ExifColorSpace(const std::string& tiff_bytes) {
  const Tiff tiff(tiff_bytes);
  if (!tiff.Valid()) return 0;
  const uint32_t exif_ifd = tiff.Offset(tiff.FirstIfd(), kExifIfd);
  if (exif_ifd == 0) return 0;
  const Tiff::Entry e = tiff.Find(exif_ifd, kColorSpace);
  if (!e.ok || e.type != kShort) return 0;
  return tiff.U16(e.value_offset);
}

DeclaredEncoding FromExifColorSpace(const std::string& tiff_bytes) {
  DeclaredEncoding declared;
  if (ExifColorSpace(tiff_bytes) == 1) {
    declared.encoding = DPEncoding::kSrgb;
    declared.evidence = "EXIF ColorSpace sRGB";
  }
  return declared;
}

// The PNG chunks before the pixels that name a transfer curve.
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
    if (type == "eXIf") return FromExifColorSpace(data);
    if (type == "IDAT" || type == "IEND") break;
    at += 12 + static_cast<size_t>(length);
  }
  return DeclaredEncoding();
}

}  // namespace

DeclaredEncoding ParseDeclaredEncoding(const std::string& bytes) {
  if (bytes.size() >= 4 && static_cast<unsigned char>(bytes[0]) == 0xFF &&
      static_cast<unsigned char>(bytes[1]) == 0xD8) {
    return FromExifColorSpace(JpegExif(bytes));
  }
  if (bytes.size() >= 8 && bytes.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0) {
    return PngDeclaredEncoding(bytes);
  }
  return FromExifColorSpace(bytes);
}

ExifLens ParseExifLens(const std::string& bytes) {
  if (bytes.size() >= 4 && static_cast<unsigned char>(bytes[0]) == 0xFF &&
      static_cast<unsigned char>(bytes[1]) == 0xD8) {
    return ParseTiff(JpegExif(bytes));
  }
  if (bytes.size() >= 8 && bytes.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0) {
    return ParseTiff(PngExif(bytes));
  }
  return ParseTiff(bytes);  // TIFF and the raw formats built on it
}

ExifLens ReadExifLens(const std::string& path) {
  return ParseExifLens(ReadHead(path));
}

}  // namespace dpsfm
