#include "dpsfm/colmap/io/png_decoder.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <utility>
#include <vector>

#include <libdeflate.h>

namespace dpsfm {
namespace {

constexpr char kSignature[] = "\x89PNG\r\n\x1a\n";
// libpng's default limits on either side (PNG_USER_WIDTH_MAX and
// PNG_USER_HEIGHT_MAX); larger files are left to OpenImageIO.
constexpr uint32_t kMaxSide = 1000000;
// Deflate's largest expansion: 258 bytes from each 2-bit code (RFC 1951).
constexpr size_t kMaxDeflateRatio = 1032;

uint32_t BigEndian32(const unsigned char* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) |
         (uint32_t{p[2]} << 8) | uint32_t{p[3]};
}

// What the chunks say: the header's fields and where the compressed pixel
// data lie (the IDAT chunks' payloads, in order).
struct PngLayout {
  int width = 0;
  int height = 0;
  int bytes_per_sample = 0;                     // 1 or 2
  int channels = 0;                             // 1 (grey) or 3 (RGB)
  std::vector<std::pair<size_t, size_t>> idat;  // offset, length
};

bool ReadHeader(const unsigned char* data, PngLayout* layout) {
  const uint32_t width = BigEndian32(data);
  const uint32_t height = BigEndian32(data + 4);
  const int bit_depth = data[8];
  const int colour_type = data[9];
  const int compression = data[10];
  const int filter = data[11];
  const int interlace = data[12];
  if (width == 0 || height == 0 || width > kMaxSide || height > kMaxSide) {
    return false;
  }
  if ((bit_depth != 8 && bit_depth != 16) ||
      (colour_type != 0 && colour_type != 2) || compression != 0 ||
      filter != 0 || interlace != 0) {
    return false;
  }
  layout->width = static_cast<int>(width);
  layout->height = static_cast<int>(height);
  layout->bytes_per_sample = bit_depth / 8;
  layout->channels = colour_type == 2 ? 3 : 1;
  return true;
}

// Walks the chunks up to IEND, checking every CRC. False for anything this
// reader leaves to OpenImageIO: a palette, transparency, a critical chunk it
// does not know, IDAT chunks apart, or any chunk out of place or damaged.
bool ReadLayout(const std::string& bytes, PngLayout* layout) {
  const auto* s = reinterpret_cast<const unsigned char*>(bytes.data());
  if (bytes.size() < 8 || bytes.compare(0, 8, kSignature, 8) != 0) {
    return false;
  }
  size_t at = 8;
  bool header = false;
  bool previous_idat = false;
  while (at + 12 <= bytes.size()) {
    const uint32_t length = BigEndian32(s + at);
    if (length > bytes.size() - at - 12) return false;
    const unsigned char* type = s + at + 4;
    const unsigned char* data = s + at + 8;
    if (libdeflate_crc32(0, type, length + 4) != BigEndian32(data + length)) {
      return false;
    }
    const std::string name(reinterpret_cast<const char*>(type), 4);
    if (!header) {
      if (name != "IHDR" || length != 13 || !ReadHeader(data, layout)) {
        return false;
      }
      header = true;
    } else if (name == "IDAT") {
      if (!layout->idat.empty() && !previous_idat) return false;
      layout->idat.emplace_back(at + 8, length);
    } else if (name == "IEND") {
      return !layout->idat.empty();
    } else if ((type[0] & 0x20) == 0 || name == "tRNS") {
      return false;  // critical (PLTE, a second IHDR, unknown) or tRNS
    }
    previous_idat = name == "IDAT";
    at += 12 + static_cast<size_t>(length);
  }
  return false;  // no IEND
}

// The IDAT payloads moved together at the first one's place: the zlib stream
// they split. Returns its length.
size_t GatherStream(const PngLayout& layout, std::string* bytes) {
  char* base = &(*bytes)[0];
  size_t end = layout.idat.front().first;
  for (const auto& [offset, length] : layout.idat) {
    std::memmove(base + end, base + offset, length);
    end += length;
  }
  return end - layout.idat.front().first;
}

// A pixel's bytes (up to six) widened to eight 16-bit lanes, so that sums
// and differences of bytes cannot wrap. The Average and Paeth filters make
// each pixel depend on the one before it; a pixel at a time in one
// register, all its channels at once, Paeth runs 2-5 times faster than a
// byte at a time (whose channels' chains spill out of the registers). Two
// forms with the same integer operations (png_decoder_test compares their
// bytes):
// - PortablePixel: plain C++ for any compiler;
// - VectorPixel: GCC's and Clang's vector extension, one SSE2 (NEON)
//   register. GCC 12 does not vectorise PortablePixel's Paeth, which then
//   takes 1.4-1.9x as long on colour frames.
struct PortablePixel {
  int16_t v[8];
};
// Bytes readable after a row's end (LoadPixel reads eight).
constexpr size_t kPixelPadding = 8;

// Reads eight bytes from `p` (the pixel's and those after it, which the
// buffers hold for the last pixel too): a load of the pixel's bytes alone
// would go through memory, and wait for the bytes it stored.
inline void LoadPixel(const uint8_t* p, PortablePixel* lanes) {
  uint8_t bytes[8];
  std::memcpy(bytes, p, sizeof(bytes));
  for (int k = 0; k < 8; ++k) lanes->v[k] = bytes[k];
}

// Stores the first `bpp` lanes' low bytes (the sums modulo 256 the filters
// define).
inline void StorePixel(const PortablePixel& lanes, int bpp, uint8_t* p) {
  uint8_t bytes[8];
  for (int k = 0; k < 8; ++k) bytes[k] = static_cast<uint8_t>(lanes.v[k]);
  std::memcpy(p, bytes, bpp);
}

// Each lane of `filtered` plus the Average predictor of its left and upper
// neighbours (the floor of their mean), modulo 256.
inline PortablePixel AddAverage(const PortablePixel& filtered,
                                const PortablePixel& left,
                                const PortablePixel& upper) {
  PortablePixel sum;
  for (int k = 0; k < 8; ++k) {
    sum.v[k] = static_cast<int16_t>(
        (filtered.v[k] + ((left.v[k] + upper.v[k]) >> 1)) & 0xFF);
  }
  return sum;
}

// Each lane of `filtered` plus the Paeth predictor (PNG 1.2, section 6.6)
// from its left, upper and upper-left neighbours (the nearest of the three
// to left + upper - upper left, ties to left, then upper), modulo 256.
inline PortablePixel AddPaeth(const PortablePixel& filtered,
                              const PortablePixel& left,
                              const PortablePixel& upper,
                              const PortablePixel& upper_left) {
  PortablePixel sum;
  for (int k = 0; k < 8; ++k) {
    const int a = left.v[k], b = upper.v[k], c = upper_left.v[k];
    const int pa = std::abs(b - c);
    const int pb = std::abs(a - c);
    const int pc = std::abs(a + b - 2 * c);
    const int nearer = pb < pa ? b : a;
    const int predictor = pc < (pb < pa ? pb : pa) ? c : nearer;
    sum.v[k] = static_cast<int16_t>((filtered.v[k] + predictor) & 0xFF);
  }
  return sum;
}

#if defined(__GNUC__)
typedef int16_t VectorPixel __attribute__((vector_size(16)));
typedef uint8_t VectorPixelBytes __attribute__((vector_size(8)));

inline void LoadPixel(const uint8_t* p, VectorPixel* lanes) {
  VectorPixelBytes bytes;
  std::memcpy(&bytes, p, sizeof(bytes));
  *lanes = __builtin_convertvector(bytes, VectorPixel);
}

inline void StorePixel(const VectorPixel& lanes, int bpp, uint8_t* p) {
  const VectorPixelBytes bytes = __builtin_convertvector(lanes, VectorPixelBytes);
  uint64_t word;
  std::memcpy(&word, &bytes, sizeof(word));
  std::memcpy(p, &word, bpp);
}

inline VectorPixel Abs(const VectorPixel& v) { return v < 0 ? -v : v; }

inline VectorPixel AddAverage(const VectorPixel& filtered,
                              const VectorPixel& left,
                              const VectorPixel& upper) {
  return (filtered + ((left + upper) >> 1)) & 0xFF;
}

inline VectorPixel AddPaeth(const VectorPixel& filtered,
                            const VectorPixel& left,
                            const VectorPixel& upper,
                            const VectorPixel& upper_left) {
  const VectorPixel pa = Abs(upper - upper_left);
  const VectorPixel pb = Abs(left - upper_left);
  const VectorPixel pc = Abs(left + upper - 2 * upper_left);
  const VectorPixel nearer = pb < pa ? upper : left;
  const VectorPixel nearer_distance = pb < pa ? pb : pa;
  return (filtered + (pc < nearer_distance ? upper_left : nearer)) & 0xFF;
}

using Pixel = VectorPixel;
#else
using Pixel = PortablePixel;
#endif

// Reverses one row's filter (PNG 1.2, section 9) in place, given the row
// above as unfiltered (zeros above the first). False for an unknown filter.
// `Bpp` (bytes per pixel) is a constant so that each byte's dependence on
// the one a pixel before it stays in registers.
template <typename Lanes, int Bpp>
bool Unfilter(int filter,
              size_t row_bytes,
              const uint8_t* prior,
              uint8_t* row) {
  switch (filter) {
    case 0:
      return true;
    case 1: {  // Sub, a pixel at a time
      uint8_t left[Bpp];
      std::memcpy(left, row, Bpp);
      for (size_t i = Bpp; i < row_bytes; i += Bpp) {
        for (int c = 0; c < Bpp; ++c) left[c] = row[i + c] += left[c];
      }
      return true;
    }
    case 2:  // Up
      for (size_t i = 0; i < row_bytes; ++i) row[i] += prior[i];
      return true;
    case 3: {  // Average
      for (int i = 0; i < Bpp; ++i) row[i] += prior[i] >> 1;
      Lanes left, upper, filtered;
      LoadPixel(row, &left);
      for (size_t i = Bpp; i < row_bytes; i += Bpp) {
        LoadPixel(prior + i, &upper);
        LoadPixel(row + i, &filtered);
        left = AddAverage(filtered, left, upper);
        StorePixel(left, Bpp, row + i);
      }
      return true;
    }
    case 4: {  // Paeth
      for (int i = 0; i < Bpp; ++i) row[i] += prior[i];
      Lanes left, upper_left, upper, filtered;
      LoadPixel(row, &left);
      LoadPixel(prior, &upper_left);
      for (size_t i = Bpp; i < row_bytes; i += Bpp) {
        LoadPixel(prior + i, &upper);
        LoadPixel(row + i, &filtered);
        left = AddPaeth(filtered, left, upper, upper_left);
        StorePixel(left, Bpp, row + i);
        upper_left = upper;
      }
      return true;
    }
    default:
      return false;
  }
}

// One unfiltered row in PNG's order (big-endian samples, R, G, B) written as
// OpenCV holds it (native samples, B, G, R) at `out`, which may lie before
// `row` in the same buffer, never after it: each pixel is read whole before
// it is written, and written no further than where the next one starts.
template <typename T, int Channels>
void StoreRow(const uint8_t* row, int width, uint8_t* out) {
  constexpr int kBytes = Channels * static_cast<int>(sizeof(T));
  for (int x = 0; x < width; ++x, row += kBytes, out += kBytes) {
    T v[Channels];
    for (int c = 0; c < Channels; ++c) {
      v[c] = sizeof(T) == 1
                 ? row[c]
                 : static_cast<T>((row[2 * c] << 8) | row[2 * c + 1]);
    }
    if (Channels == 3) std::swap(v[0], v[2]);
    std::memcpy(out, v, kBytes);
  }
}

// Unfilters the inflated rows (each a filter byte, then the row) and stores
// each at its place in the frame, from the buffer's start. False for an
// unknown filter.
template <typename T, int Channels>
bool UnfilterRows(int width, int height, uint8_t* buffer) {
  constexpr int kBpp = Channels * static_cast<int>(sizeof(T));
  const size_t row_bytes = static_cast<size_t>(width) * kBpp;
  std::vector<uint8_t> prior(row_bytes + kPixelPadding, 0);
  for (int y = 0; y < height; ++y) {
    uint8_t* row = buffer + y * (row_bytes + 1);
    if (!Unfilter<Pixel, kBpp>(row[0], row_bytes, prior.data(), row + 1)) {
      return false;
    }
    std::memcpy(prior.data(), row + 1, row_bytes);
    StoreRow<T, Channels>(row + 1, width, buffer + y * row_bytes);
  }
  return true;
}

bool UnfilterFrame(const PngLayout& layout, uint8_t* buffer) {
  const int w = layout.width;
  const int h = layout.height;
  if (layout.bytes_per_sample == 1) {
    return layout.channels == 1 ? UnfilterRows<uint8_t, 1>(w, h, buffer)
                                : UnfilterRows<uint8_t, 3>(w, h, buffer);
  }
  return layout.channels == 1 ? UnfilterRows<uint16_t, 1>(w, h, buffer)
                              : UnfilterRows<uint16_t, 3>(w, h, buffer);
}

}  // namespace

PngDecoding DecodePng(std::string* bytes, cv::Mat* pixels) {
  PngLayout layout;
  if (!ReadLayout(*bytes, &layout)) return PngDecoding::kNotDecoded;
  const size_t row_bytes = static_cast<size_t>(layout.width) * layout.channels *
                           layout.bytes_per_sample;
  const size_t stream_bytes = layout.height * (row_bytes + 1);
  // The header is checked against the data before the frame is allocated:
  // deflate expands at most 1032:1, so a header claiming more than its IDAT
  // chunks can hold is corrupt (a 10^6 x 10^6 header over a few bytes
  // would otherwise allocate terabytes before inflating).
  size_t compressed_bytes = 0;
  for (const auto& chunk : layout.idat) compressed_bytes += chunk.second;
  if (stream_bytes / kMaxDeflateRatio > compressed_bytes + 1) {
    return PngDecoding::kFailed;
  }

  // The frame's own matrix is the inflate buffer (with the rows' filter
  // bytes and LoadPixel's padding, a few rows more than the frame): each row
  // is unfiltered where it was inflated and stored at its place in the
  // frame, which never lies after it, so a frame is held once.
  const int type = CV_MAKETYPE(layout.bytes_per_sample == 1 ? CV_8U : CV_16U,
                               layout.channels);
  const int spare_rows = static_cast<int>(
      (layout.height + kPixelPadding + row_bytes - 1) / row_bytes);
  cv::Mat storage(layout.height + spare_rows, layout.width, type);

  std::unique_ptr<libdeflate_decompressor, void (*)(libdeflate_decompressor*)>
      decompressor(libdeflate_alloc_decompressor(),
                   libdeflate_free_decompressor);
  if (!decompressor) return PngDecoding::kNotDecoded;
  const size_t compressed = GatherStream(layout, bytes);
  size_t inflated = 0;
  const libdeflate_result result =
      libdeflate_zlib_decompress(decompressor.get(),
                                 bytes->data() + layout.idat.front().first,
                                 compressed,
                                 storage.data,
                                 stream_bytes,
                                 &inflated);
  std::string().swap(*bytes);
  if (result != LIBDEFLATE_SUCCESS || inflated != stream_bytes ||
      !UnfilterFrame(layout, storage.data)) {
    return PngDecoding::kFailed;
  }
  *pixels = storage.rowRange(0, layout.height);
  return PngDecoding::kDecoded;
}

namespace internal {
namespace {

template <typename Lanes>
bool UnfilterRowWith(int filter,
                     int bytes_per_pixel,
                     size_t row_bytes,
                     const uint8_t* prior,
                     uint8_t* row) {
  switch (bytes_per_pixel) {
    case 1:
      return Unfilter<Lanes, 1>(filter, row_bytes, prior, row);
    case 2:
      return Unfilter<Lanes, 2>(filter, row_bytes, prior, row);
    case 3:
      return Unfilter<Lanes, 3>(filter, row_bytes, prior, row);
    case 4:
      return Unfilter<Lanes, 4>(filter, row_bytes, prior, row);
    case 6:
      return Unfilter<Lanes, 6>(filter, row_bytes, prior, row);
    case 8:
      return Unfilter<Lanes, 8>(filter, row_bytes, prior, row);
    default:
      return false;
  }
}

}  // namespace

bool UnfilterRowForTest(int filter,
                        int bytes_per_pixel,
                        size_t row_bytes,
                        const uint8_t* prior,
                        uint8_t* row,
                        bool portable) {
  return portable ? UnfilterRowWith<PortablePixel>(
                        filter, bytes_per_pixel, row_bytes, prior, row)
                  : UnfilterRowWith<Pixel>(
                        filter, bytes_per_pixel, row_bytes, prior, row);
}

}  // namespace internal

}  // namespace dpsfm
