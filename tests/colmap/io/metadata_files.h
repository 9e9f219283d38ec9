// Image files with metadata written byte by byte, for the readers' tests:
// an oracle that shares no code with Exiv2 or the product.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

namespace dpsfm {
namespace test {

// A TIFF block written byte by byte, in either byte order: IFD0, an Exif
// IFD (pointed to from IFD0) and optionally a maker-note IFD (the value of
// the Exif IFD's MakerNote entry, offsets from the TIFF header as Canon
// writes them). Values longer than 4 bytes go into a data area at the end.
class TiffWriter {
 public:
  explicit TiffWriter(bool big_endian) : big_(big_endian) {}

  struct Entry {
    uint16_t tag, type;
    uint32_t count;
    std::string value;  // already in the file's byte order
  };
  std::vector<Entry> ifd0, exif, maker_note;

  std::string U16(uint16_t v) const {
    std::string out(2, '\0');
    out[big_ ? 0 : 1] = static_cast<char>(v >> 8);
    out[big_ ? 1 : 0] = static_cast<char>(v & 0xff);
    return out;
  }
  std::string U32(uint32_t v) const {
    std::string out(4, '\0');
    for (int i = 0; i < 4; ++i) {
      out[big_ ? 3 - i : i] = static_cast<char>((v >> (8 * i)) & 0xff);
    }
    return out;
  }
  Entry Ascii(uint16_t tag, const std::string& text) const {
    return {tag,
            2,
            static_cast<uint32_t>(text.size() + 1),
            text + std::string(1, '\0')};
  }
  Entry Rational(uint16_t tag, uint32_t num, uint32_t den) const {
    return {tag, 5, 1, U32(num) + U32(den)};
  }
  Entry Shorts(uint16_t tag, const std::vector<uint16_t>& values) const {
    std::string bytes;
    for (uint16_t v : values) bytes += U16(v);
    return {tag, 3, static_cast<uint32_t>(values.size()), bytes};
  }

  std::string Bytes() const {
    auto ifd_size = [](const std::vector<Entry>& e) {
      return static_cast<uint32_t>(2 + 12 * e.size() + 4);
    };
    std::vector<Entry> ifd0_entries = ifd0;
    const bool with_exif = !exif.empty() || !maker_note.empty();
    if (with_exif) ifd0_entries.push_back({0x8769, 4, 1, ""});
    std::vector<Entry> exif_entries = exif;
    if (!maker_note.empty()) exif_entries.push_back({0x927C, 7, 0, ""});
    const uint32_t ifd0_at = 8;
    const uint32_t exif_at = ifd0_at + ifd_size(ifd0_entries);
    const uint32_t note_at = exif_at + ifd_size(exif_entries);
    const uint32_t note_size = ifd_size(maker_note);
    uint32_t data_at = note_at + (maker_note.empty() ? 0 : note_size);
    std::string data;
    auto write_ifd = [&](std::vector<Entry> entries) {
      std::string out = U16(static_cast<uint16_t>(entries.size()));
      for (Entry& e : entries) {
        if (e.tag == 0x8769) e.value = U32(exif_at);
        out += U16(e.tag) + U16(e.type);
        if (e.tag == 0x927C && e.type == 7) {
          out += U32(note_size) + U32(note_at);
          continue;
        }
        out += U32(e.count);
        if (e.value.size() <= 4) {
          out += e.value + std::string(4 - e.value.size(), '\0');
        } else {
          out += U32(data_at + static_cast<uint32_t>(data.size()));
          data += e.value;
        }
      }
      return out + U32(0);
    };
    std::string out = big_ ? "MM" : "II";
    out += U16(42) + U32(ifd0_at);
    out += write_ifd(ifd0_entries);
    if (with_exif) out += write_ifd(exif_entries);
    if (!maker_note.empty()) out += write_ifd(maker_note);
    return out + data;
  }

 private:
  bool big_;
};

// A small JPEG with `tiff` as its APP1 Exif segment (inserted after SOI).
inline std::string JpegWithExif(const std::string& tiff) {
  const std::string payload = std::string("Exif\0\0", 6) + tiff;
  std::string app1 = "\xFF\xE1";
  const uint16_t length = static_cast<uint16_t>(payload.size() + 2);
  app1.push_back(static_cast<char>(length >> 8));
  app1.push_back(static_cast<char>(length & 0xff));
  app1 += payload;
  std::vector<uchar> jpeg;
  cv::imencode(
      ".jpg", cv::Mat(16, 16, CV_8UC3, cv::Scalar(90, 120, 200)), jpeg);
  const std::string bytes(jpeg.begin(), jpeg.end());
  return bytes.substr(0, 2) + app1 + bytes.substr(2);
}

// A small PNG with `tiff` as an eXIf chunk after IHDR (CRC not checked by
// readers of metadata; written as zeros).
inline std::string PngWithExif(const std::string& tiff) {
  std::vector<uchar> png;
  cv::imencode(".png", cv::Mat(8, 8, CV_8UC1, cv::Scalar(7)), png);
  const std::string bytes(png.begin(), png.end());
  const size_t after_ihdr = 8 + 4 + 4 + 13 + 4;
  std::string chunk;
  const uint32_t n = static_cast<uint32_t>(tiff.size());
  for (int i = 3; i >= 0; --i) chunk.push_back(static_cast<char>(n >> (8 * i)));
  chunk += "eXIf" + tiff + std::string(4, '\0');
  return bytes.substr(0, after_ihdr) + chunk + bytes.substr(after_ihdr);
}

// An image encoded as PNG with one more chunk (type, data) after IHDR, its
// CRC-32 computed bit by bit (PNG's polynomial 0xEDB88320).
inline std::string PngWithChunk(const cv::Mat& image,
                         const std::string& type,
                         const std::string& data) {
  std::vector<uchar> png;
  cv::imencode(".png", image, png);
  const std::string bytes(png.begin(), png.end());
  const size_t after_ihdr = 8 + 4 + 4 + 13 + 4;
  std::string chunk;
  const uint32_t n = static_cast<uint32_t>(data.size());
  for (int i = 3; i >= 0; --i) chunk.push_back(static_cast<char>(n >> (8 * i)));
  uint32_t crc = 0xFFFFFFFFu;
  for (const char c : type + data) {
    crc ^= static_cast<uint8_t>(c);
    for (int k = 0; k < 8; ++k)
      crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  crc ^= 0xFFFFFFFFu;
  chunk += type + data;
  for (int i = 3; i >= 0; --i)
    chunk.push_back(static_cast<char>(crc >> (8 * i)));
  return bytes.substr(0, after_ihdr) + chunk + bytes.substr(after_ihdr);
}

inline std::string BigEndian(uint32_t v) {
  std::string s;
  for (int i = 3; i >= 0; --i) s.push_back(static_cast<char>(v >> (8 * i)));
  return s;
}

}  // namespace test
}  // namespace dpsfm
