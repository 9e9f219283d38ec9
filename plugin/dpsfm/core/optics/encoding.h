// How DP frames encode light, and bringing them to linear light.
//
// Defocus blur is a convolution of scene radiance: it holds in linear light,
// not in the sRGB-encoded values of 8-bit exports and phone captures (the
// encoding bends every blurred edge, the more the higher its contrast). The
// blur search and the calibrator therefore work on linear light, whatever
// the frames were given in.
#pragma once

#include <string>

#include <opencv2/core.hpp>

namespace dpsfm {

enum class DPEncoding {
  kAuto,    // decided per file (colmap/io/dp_images.h, DecideEncoding)
  kLinear,  // values proportional to light (16-bit DPRSplit output, raw)
  kSrgb,    // the sRGB transfer curve (8-bit exports, phone JPEGs)
};

// "auto", "linear", "srgb"; throws std::invalid_argument for anything else.
DPEncoding ParseDPEncoding(const std::string& name);
bool IsDPEncodingName(const std::string& name);
const char* DPEncodingName(DPEncoding encoding);

// The sRGB decoding curve (IEC 61966-2-1) of a value in [0, 1]:
// v / 12.92 below 0.04045, ((v + 0.055) / 1.055)^2.4 above.
double SrgbToLinear(double encoded);

// Brings a CV_32F image with values in [0, 1] from `encoding` to linear
// light in place (kLinear: unchanged). kAuto is not an encoding of pixels:
// std::invalid_argument.
void DecodeToLinearLight(DPEncoding encoding, cv::Mat* image);

}  // namespace dpsfm
