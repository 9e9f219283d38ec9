// Decoding DP frames: the libdeflate PNG reader (colmap/io/png_decoder.h)
// against OpenImageIO's (libpng and zlib: how every PNG frame was decoded
// before it), on one synthetic frame (a smooth scene with sensor noise)
// written by OpenImageIO with each of libpng's row filters, at 16 and 8 bits
// in colour and 16 bits in grey. Prints seconds per decode (median of N
// rounds), the ratio, and whether the two decodes are the same bits; never
// asserts.
//
//   png_decode_bench [--rounds N] [--width W] [--height H]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <opencv2/core.hpp>

#include "../../tests/colmap/io/frame_oracle.h"
#include "../bench_timing.h"
#include "dpsfm/colmap/io/png_decoder.h"

namespace {

using namespace dpsfm;

using bench::Now;

// A 16-bit colour frame in RGB order: smooth shading, edges and noise, so
// that the filters predict as they do on photographs.
cv::Mat SyntheticFrame(int width, int height) {
  cv::Mat frame(height, width, CV_16UC3);
  cv::RNG rng(31);
  for (int y = 0; y < height; ++y) {
    auto* row = frame.ptr<cv::Vec3w>(y);
    for (int x = 0; x < width; ++x) {
      const double shade = 2.0 + std::sin(x / 53.0) + std::cos(y / 71.0) +
                           (((x / 97) + (y / 89)) % 2 ? 0.5 : 0.0);
      for (int c = 0; c < 3; ++c) {
        const double v = 9000.0 * shade * (1.0 + 0.1 * c) + rng.gaussian(150);
        row[x][c] = cv::saturate_cast<uint16_t>(v);
      }
    }
  }
  return frame;
}

// The frame as a PNG file's bytes, written by OpenImageIO with libpng's
// filter flags (png:filter), or "" if it cannot.
std::string EncodeWithFilter(const cv::Mat& frame, int filter) {
  const std::string path =
      (std::filesystem::temp_directory_path() / "dpsfm_png_decode_bench.png")
          .string();
  std::unique_ptr<OIIO::ImageOutput> out = OIIO::ImageOutput::create(path);
  const OIIO::TypeDesc type =
      frame.depth() == CV_8U ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16;
  OIIO::ImageSpec spec(frame.cols, frame.rows, frame.channels(), type);
  spec.attribute("png:filter", filter);
  if (!out || !out->open(path, spec) || !out->write_image(type, frame.data) ||
      !out->close()) {
    return "";
  }
  std::ifstream file(path, std::ios::binary);
  std::stringstream bytes;
  bytes << file.rdbuf();
  std::filesystem::remove(path);
  return bytes.str();
}

struct Filter {
  const char* name;
  int flags;  // libpng's PNG_FILTER_* bits
};

}  // namespace

int main(int argc, char** argv) {
  int rounds = 3, width = 3000, height = 2000;
  for (int i = 1; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--rounds") == 0) rounds = std::atoi(argv[++i]);
    if (std::strcmp(argv[i], "--width") == 0) width = std::atoi(argv[++i]);
    if (std::strcmp(argv[i], "--height") == 0) height = std::atoi(argv[++i]);
  }
  const cv::Mat colour16 = SyntheticFrame(width, height);
  cv::Mat colour8, grey16;
  colour16.convertTo(colour8, CV_8U, 1.0 / 257.0);
  cv::extractChannel(colour16, grey16, 1);
  struct Frame {
    const char* name;
    const cv::Mat* pixels;
  };
  const std::vector<Frame> frames = {{"16-bit colour", &colour16},
                                     {"8-bit colour", &colour8},
                                     {"16-bit grey", &grey16}};
  const std::vector<Filter> filters = {{"Sub (as OpenCV writes)", 0x10},
                                       {"Up", 0x20},
                                       {"Average", 0x40},
                                       {"Paeth", 0x80},
                                       {"libpng's choice", 0xF8}};
  std::printf(
      "A %d x %d frame decoded from memory, seconds per decode, median of %d "
      "rounds\n",
      width,
      height,
      rounds);
  std::printf(
      "| frame | filters | PNG reader (libdeflate) | OpenImageIO | "
      "OpenImageIO / reader | same bits |\n|---|---|---|---|---|---|\n");
  for (const Frame& frame : frames) {
    for (const Filter& filter : filters) {
      const std::string file = EncodeWithFilter(*frame.pixels, filter.flags);
      if (file.empty()) {
        std::printf("| %s | %s | (OpenImageIO could not write it) |\n",
                    frame.name,
                    filter.name);
        continue;
      }
      cv::Mat ours, theirs;
      const double ours_s = bench::MedianOf(rounds, [&] {
        std::string bytes = file;  // DecodePng consumes its bytes
        const double start = Now();
        const bool decoded = DecodePng(&bytes, &ours) == PngDecoding::kDecoded;
        const double seconds = Now() - start;
        if (!decoded) ours.release();
        return seconds;
      });
      const double theirs_s = bench::MedianOf(rounds, [&] {
        const double start = Now();
        theirs = test::DecodedByOpenImageIO(file);
        return Now() - start;
      });
      std::printf("| %s | %s | %.3f | %.3f | %.2f | %s |\n",
                  frame.name,
                  filter.name,
                  ours_s,
                  theirs_s,
                  theirs_s / ours_s,
                  test::SameBits(ours, theirs) ? "yes" : "NO");
    }
  }
  return 0;
}
