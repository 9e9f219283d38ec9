// The cameras' metadata read by Exiv2 (built with -DDPSFM_WITH_EXIV2=ON).
#include "dpsfm/colmap/io/image_metadata_reader.h"

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <mutex>
#include <sstream>
#include <vector>

// Exiv2 0.27's factory returns std::auto_ptr (deprecated in C++11).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
#include <exiv2/exiv2.hpp>

#include "dpsfm/colmap/io/text.h"

namespace dpsfm {
namespace {

// Exiv2 once per process: its messages muted (a file's problems come back
// as CameraMetadata::error, in this product's words), CR3 and HEIF on.
void InitExiv2() {
  static std::once_flag once;
  std::call_once(once, [] {
    Exiv2::LogMsg::setLevel(Exiv2::LogMsg::mute);
    Exiv2::XmpParser::initialize();
#ifdef EXV_ENABLE_BMFF
    Exiv2::enableBMFF(true);
#endif
  });
}

// The datum of `key`, null if absent (or not a key this Exiv2 knows).
const Exiv2::Exifdatum* Find(const Exiv2::ExifData& exif, const char* key) {
  try {
    const auto it = exif.findKey(Exiv2::ExifKey(key));
    return it == exif.end() ? nullptr : &*it;
  } catch (const std::exception&) {
    return nullptr;
  }
}

int64_t Integer(const Exiv2::Exifdatum& datum, long i) {
#if EXIV2_TEST_VERSION(0, 28, 0)
  return datum.toInt64(i);
#else
  return datum.toLong(i);
#endif
}

std::string Text(const Exiv2::ExifData& exif, const char* key) {
  const Exiv2::Exifdatum* datum = Find(exif, key);
  if (datum == nullptr) return "";
  std::string text = datum->toString();
  text = text.substr(0, text.find('\0'));
  return Trim(text);
}

// A RATIONAL as the file holds it, num / den exactly (23.47 mm would read
// as 23.5 through the printed form); unsigned rationals as unsigned.
// False when absent, not a rational or den 0. *raw_num gets the numerator
// as stored (SubjectDistance's 0xFFFFFFFF is infinity).
bool Rational(const Exiv2::ExifData& exif,
              const char* key,
              double* value,
              uint32_t* raw_num = nullptr) {
  const Exiv2::Exifdatum* datum = Find(exif, key);
  if (datum == nullptr || datum->count() < 1) return false;
  const Exiv2::TypeId type = datum->typeId();
  if (type != Exiv2::unsignedRational && type != Exiv2::signedRational) {
    return false;
  }
  const Exiv2::Rational r = datum->toRational(0);
  if (r.second == 0) return false;
  if (type == Exiv2::unsignedRational) {
    const uint32_t num = static_cast<uint32_t>(r.first);
    const uint32_t den = static_cast<uint32_t>(r.second);
    if (raw_num != nullptr) *raw_num = num;
    *value = static_cast<double>(num) / den;
  } else {
    if (raw_num != nullptr) *raw_num = static_cast<uint32_t>(r.first);
    *value = static_cast<double>(r.first) / r.second;
  }
  return std::isfinite(*value);
}

MetadataNumber PositiveRational(const Exiv2::ExifData& exif, const char* key) {
  MetadataNumber number;
  double value = 0;
  if (Rational(exif, key, &value) && value > 0) {
    number.value = value;
    number.tag = key;
  }
  return number;
}

// FocalPlaneXResolution (pixels per unit on the sensor) and its unit
// (FocalPlaneResolutionUnit: 2 inch, the default; 3 cm; 4 mm and 5 um as
// TIFF/EP and DNG add), in the Exif IFD or, as TIFF/EP raws write it, in
// IFD0.
MetadataNumber PixelPitch(const Exiv2::ExifData& exif) {
  static const char* const kKeys[2][2] = {
      {"Exif.Photo.FocalPlaneXResolution",
       "Exif.Photo.FocalPlaneResolutionUnit"},
      {"Exif.Image.FocalPlaneXResolution",
       "Exif.Image.FocalPlaneResolutionUnit"}};
  for (const auto& keys : kKeys) {
    double per_unit = 0;
    if (!Rational(exif, keys[0], &per_unit) || !(per_unit > 0)) continue;
    int64_t unit = 2;
    if (const Exiv2::Exifdatum* u = Find(exif, keys[1])) {
      if (u->count() >= 1) unit = Integer(*u, 0);
    }
    const double um_per_unit = unit == 2   ? 25400
                               : unit == 3 ? 10000
                               : unit == 4 ? 1000
                               : unit == 5 ? 1
                                           : 0;
    if (um_per_unit == 0) continue;
    MetadataNumber pitch;
    pitch.value = um_per_unit / per_unit;
    pitch.tag = keys[0];
    return pitch;
  }
  return MetadataNumber();
}

// One of Canon's windows: upper and lower in cm, 0 when not recorded and
// 65535 (-1 as a signed short) for infinity. A distance when both are
// finite and the window is no wider than a factor 3 (one wider says too
// little to use); else *note says why not.
bool CanonWindow(const Exiv2::ExifData& exif,
                 const char* upper_key,
                 const char* lower_key,
                 const std::string& tag,
                 RecordedFocus* focus,
                 std::string* note) {
  const Exiv2::Exifdatum* upper = Find(exif, upper_key);
  const Exiv2::Exifdatum* lower = Find(exif, lower_key);
  auto value = [](const Exiv2::Exifdatum* datum) -> int64_t {
    // As unsigned 16-bit values: 0xFFFF is infinity whichever the type; an
    // entry the record does not reach is not recorded.
    return datum != nullptr && datum->count() >= 1 ? Integer(*datum, 0) & 0xFFFF
                                                   : 0;
  };
  if (value(upper) == 0 && value(lower) == 0 &&
      (upper == nullptr || upper->count() < 1)) {
    return false;  // no window in this record
  }
  const int64_t u = value(upper);
  const int64_t l = value(lower);
  std::ostringstream why;
  if (u == 0 || l == 0) {
    why << tag << " is " << l << "-" << u << " cm: not recorded";
  } else if (u == 0xFFFF || l == 0xFFFF) {
    why << tag << " is open (" << (l == 0xFFFF ? std::string("infinity")
                                                : std::to_string(l) + " cm")
        << " to infinity)";
  } else if (u < l) {
    why << tag << " is " << l << "-" << u << " cm, its upper end below its "
        << "lower";
  } else if (u > 3 * l) {
    why << tag << " is " << l << "-" << u << " cm, wider than a factor 3";
  } else {
    focus->lower_mm = 10.0 * l;
    focus->upper_mm = 10.0 * u;
    focus->distance_mm = 0.5 * (focus->lower_mm + focus->upper_mm);
    focus->bracket = static_cast<double>(u - l) / static_cast<double>(u + l);
    focus->tag = tag;
    return true;
  }
  if (note->empty()) *note = why.str();
  return false;
}

// A distance Exiv2 prints in metres ("1.26 m"), for the makers' notes whose
// encoded focus distance it decodes.
bool PrintedMetres(const Exiv2::ExifData& exif,
                   const char* key,
                   RecordedFocus* focus,
                   std::string* note) {
  const Exiv2::Exifdatum* datum = Find(exif, key);
  if (datum == nullptr) return false;
  const std::string printed = Trim(datum->print(&exif));
  char* end = nullptr;
  const double metres = std::strtod(printed.c_str(), &end);
  if (end != printed.c_str() && Trim(end) == "m" && std::isfinite(metres) &&
      metres > 0) {
    focus->distance_mm = 1000 * metres;
    focus->tag = key;
    return true;
  }
  if (note->empty()) {
    *note = std::string(key) + " is '" + printed + "': no distance";
  }
  return false;
}

// The recorded focus, in this order: Canon's window in FileInfo (R-series
// bodies), then in ShotInfo (older bodies), EXIF SubjectDistance, then the
// distances Exiv2 decodes from other makers' notes.
RecordedFocus Focus(const Exiv2::ExifData& exif, std::string* note) {
  RecordedFocus focus;
  if (CanonWindow(exif,
                  "Exif.CanonFi.FocusDistanceUpper",
                  "Exif.CanonFi.FocusDistanceLower",
                  "Exif.CanonFi.FocusDistanceUpper/Lower",
                  &focus,
                  note) ||
      CanonWindow(exif,
                  "Exif.CanonSi.SubjectDistance",
                  "Exif.CanonSi.0x0014",
                  "Exif.CanonSi.0x0013/0x0014 (ShotInfo 19-20)",
                  &focus,
                  note)) {
    return focus;
  }
  double metres = 0;
  uint32_t raw = 0;
  if (Rational(exif, "Exif.Photo.SubjectDistance", &metres, &raw)) {
    if (raw != 0 && raw != 0xFFFFFFFFu && metres > 0) {
      focus.distance_mm = 1000 * metres;
      focus.tag = "Exif.Photo.SubjectDistance";
      return focus;
    }
    if (note->empty()) {
      *note = std::string("Exif.Photo.SubjectDistance is ") +
              (raw == 0 ? "0: unknown" : "infinity");
    }
  }
  for (const char* key :
       {"Exif.NikonLd2.FocusDistance", "Exif.NikonLd3.FocusDistance"}) {
    if (PrintedMetres(exif, key, &focus, note)) return focus;
  }
  return focus;
}

CameraMetadata FromExif(const Exiv2::ExifData& exif) {
  CameraMetadata m;
  m.make = Text(exif, "Exif.Image.Make");
  m.model = Text(exif, "Exif.Image.Model");
  m.lens_model = Text(exif, "Exif.Photo.LensModel");
  if (m.lens_model.empty()) m.lens_model = Text(exif, "Exif.Canon.LensModel");
  m.focal_length_mm = PositiveRational(exif, "Exif.Photo.FocalLength");
  m.f_number = PositiveRational(exif, "Exif.Photo.FNumber");
  m.pixel_pitch_um = PixelPitch(exif);
  m.focus = Focus(exif, &m.focus_note);
  if (m.focus.distance_mm > 0) m.focus_note.clear();
  return m;
}

// The metadata of the image `open` opens, when `known` says Exiv2 knows its
// format; never throws.
template <typename Known, typename Open>
CameraMetadata Read(Known known, Open open) {
  InitExiv2();
  CameraMetadata m;
  bool is_image = false;
  try {
    is_image = known();
  } catch (...) {
    // Too short for any format's signature.
  }
  if (!is_image) {
    m.error = "not an image format whose metadata can be read";
    return m;
  }
  try {
    auto image = open();
    image->readMetadata();
    m = FromExif(image->exifData());
  } catch (...) {
    // Exiv2 parses untrusted bytes: whatever it throws (its own errors,
    // std::bad_alloc on a length it believed) is that file's problem,
    // never the run's.
    m = CameraMetadata();
    m.error = "its metadata is truncated or corrupt";
  }
  return m;
}

DeclaredEncoding FromColorSpace(const Exiv2::ExifData& exif) {
  DeclaredEncoding declared;
  const Exiv2::Exifdatum* space = Find(exif, "Exif.Photo.ColorSpace");
  if (space != nullptr && space->count() >= 1 && Integer(*space, 0) == 1) {
    declared.encoding = DPEncoding::kSrgb;
    declared.evidence = "EXIF ColorSpace sRGB";
  }
  return declared;
}

}  // namespace

namespace internal {

CameraMetadata ReadMetadataFile(const std::string& path) {
  return Read(
      [&] {
        return Exiv2::ImageFactory::getType(path) != Exiv2::ImageType::none;
      },
      [&] { return Exiv2::ImageFactory::open(path); });
}

CameraMetadata ParseMetadataBytes(const std::string& bytes) {
  const auto* data = reinterpret_cast<const Exiv2::byte*>(bytes.data());
  const long size = static_cast<long>(bytes.size());
  return Read(
      [&] {
        return Exiv2::ImageFactory::getType(data, size) !=
               Exiv2::ImageType::none;
      },
      [&] { return Exiv2::ImageFactory::open(data, size); });
}

DeclaredEncoding ExifEncoding(const std::string& bytes) {
  InitExiv2();
  try {
    const auto* data = reinterpret_cast<const Exiv2::byte*>(bytes.data());
    const long size = static_cast<long>(bytes.size());
    if (Exiv2::ImageFactory::getType(data, size) == Exiv2::ImageType::none) {
      return DeclaredEncoding();
    }
    auto image = Exiv2::ImageFactory::open(data, size);
    image->readMetadata();
    return FromColorSpace(image->exifData());
  } catch (...) {
    return DeclaredEncoding();  // unreadable metadata: it says nothing
  }
}

// EXIF ColorSpace of a bare TIFF structure (a PNG's eXIf chunk).
DeclaredEncoding ExifBlockEncoding(const std::string& tiff) {
  InitExiv2();
  try {
    Exiv2::ExifData exif;
    Exiv2::ExifParser::decode(exif,
                              reinterpret_cast<const Exiv2::byte*>(tiff.data()),
                              static_cast<uint32_t>(tiff.size()));
    return FromColorSpace(exif);
  } catch (...) {
    return DeclaredEncoding();  // unreadable: it says nothing
  }
}

}  // namespace internal
}  // namespace dpsfm

#pragma GCC diagnostic pop
