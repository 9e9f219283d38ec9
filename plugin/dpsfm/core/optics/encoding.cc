#include "dpsfm/core/optics/encoding.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace dpsfm {

DPEncoding ParseDPEncoding(const std::string& name) {
  if (name == "auto") return DPEncoding::kAuto;
  if (name == "linear") return DPEncoding::kLinear;
  if (name == "srgb") return DPEncoding::kSrgb;
  throw std::invalid_argument("unknown DP frame encoding '" + name +
                              "' (expected auto, linear or srgb)");
}

bool IsDPEncodingName(const std::string& name) {
  return name == "auto" || name == "linear" || name == "srgb";
}

const char* DPEncodingName(DPEncoding encoding) {
  switch (encoding) {
    case DPEncoding::kAuto:
      return "auto";
    case DPEncoding::kLinear:
      return "linear";
    case DPEncoding::kSrgb:
      return "srgb";
  }
  return "?";
}

double SrgbToLinear(double encoded) {
  if (encoded <= 0.04045) return encoded / 12.92;
  return std::pow((encoded + 0.055) / 1.055, 2.4);
}

void DecodeToLinearLight(DPEncoding encoding, cv::Mat* image) {
  if (encoding == DPEncoding::kAuto) {
    throw std::invalid_argument(
        "DecodeToLinearLight needs a decided encoding, not auto");
  }
  if (encoding == DPEncoding::kLinear) return;
  CV_Assert(image->depth() == CV_32F);
  // A pow per value is the plain reading of the standard; frames are read
  // once per view, so a table buys nothing measurable.
  cv::Mat values = image->reshape(1);  // the same pixels, one per channel
  values.forEach<float>([](float& v, const int*) {
    v = static_cast<float>(SrgbToLinear(std::min(std::max(v, 0.0f), 1.0f)));
  });
}

}  // namespace dpsfm
