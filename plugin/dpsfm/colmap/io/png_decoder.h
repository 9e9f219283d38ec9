// PNG frames decoded with libdeflate, for the kinds DP frames come in.
//
// Decoding a DP frame is mostly inflating its pixels: libpng (through
// OpenImageIO) inflates with zlib, at 0.22 s for a 3000 x 2000 16-bit colour
// frame where libdeflate takes 0.10 s; it decodes only whole buffers, which
// libpng cannot use, hence this reader. It takes the plain PNGs cameras'
// tools and OpenCV write (8- or 16-bit grey or colour, not interlaced, no
// transparency, every chunk's CRC right) and leaves every other file to
// OpenImageIO, so that what it decodes is what OpenImageIO would, to the bit.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

namespace dpsfm {

enum class PngDecoding {
  kDecoded,     // *pixels holds the frame; *bytes was consumed
  kNotDecoded,  // not a PNG of the kinds above; *bytes is as it was
  kFailed,      // such a PNG, but its pixel data are corrupt; *bytes was
                // consumed (the caller decodes the file again by name, so
                // that OpenImageIO words the error)
};

// Decodes a PNG file's whole bytes into pixels as OpenCV's decoder gives them
// (CV_8U or CV_16U, one channel or three in B, G, R order). The bytes are
// the working buffer: the compressed stream is gathered in place, and they
// are released before the pixels are unfiltered, so that a frame is held
// compressed and decoded at once only while it is inflated.
PngDecoding DecodePng(std::string* bytes, cv::Mat* pixels);

namespace internal {

// One row's PNG filter (0-4) reversed in place, given the row above as
// unfiltered, with the decoder's pixel lanes or (`portable`) the plain C++
// ones every compiler has, for the tests that compare the two. The row and
// the prior row hold 8 readable bytes after row_bytes; bytes_per_pixel is
// 1, 2, 3, 4, 6 or 8. False for an unknown filter or pixel size.
bool UnfilterRowForTest(int filter,
                        int bytes_per_pixel,
                        size_t row_bytes,
                        const uint8_t* prior,
                        uint8_t* row,
                        bool portable);

}  // namespace internal

}  // namespace dpsfm
