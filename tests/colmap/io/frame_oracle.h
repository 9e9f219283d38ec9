// What a frame is, decided without the plugin's readers: OpenImageIO's own
// decode of a file's bytes, and equality to the bit. Shared by the reading
// tests and benchmarks/colmap/png_decode_bench.
#pragma once

#include <memory>
#include <string>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "dpsfm/core/util/matrices.h"

namespace dpsfm {
namespace test {

// OpenImageIO's decode of an 8- or 16-bit image file's bytes, decoded in
// memory, colour in B, G, R order (as the plugin decoded every frame before
// its PNG reader); empty if OpenImageIO cannot decode them.
inline cv::Mat DecodedByOpenImageIO(const std::string& bytes) {
  OIIO::Filesystem::IOMemReader memory(bytes.data(), bytes.size());
  std::unique_ptr<OIIO::ImageInput> input =
      OIIO::ImageInput::open("frame.png", nullptr, &memory);
  if (!input) {
    OIIO::geterror();  // clears OpenImageIO's per-thread error
    return cv::Mat();
  }
  const OIIO::ImageSpec& spec = input->spec();
  const int depth = spec.format == OIIO::TypeDesc::UINT8 ? CV_8U : CV_16U;
  cv::Mat pixels(spec.height, spec.width, CV_MAKETYPE(depth, spec.nchannels));
  if (!input->read_image(
          0, 0, 0, spec.nchannels, OIIO::TypeDesc::UNKNOWN, pixels.data)) {
    input->geterror();
    return cv::Mat();
  }
  if (spec.nchannels == 3) cv::cvtColor(pixels, pixels, cv::COLOR_RGB2BGR);
  return pixels;
}

// Whether two matrices hold the same bits: neither empty, the same size and
// type, and every byte of every row equal (so 0.0 and -0.0 differ; the
// core's SameBytes, with an empty decode never a match).
inline bool SameBits(const cv::Mat& a, const cv::Mat& b) {
  return !a.empty() && SameBytes(a, b);
}

}  // namespace test
}  // namespace dpsfm
