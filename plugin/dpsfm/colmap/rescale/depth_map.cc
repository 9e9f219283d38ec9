// COLMAP depth maps (stereo/depth_maps/*.bin): "W&H&C&" then float32 values;
// the valid (> 0) depths are scaled.
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>

#include "dpsfm/colmap/rescale/byte_fields.h"
#include "dpsfm/colmap/rescale/rescale.h"

namespace dpsfm {

using rescale::Corrupt;
using rescale::Load;
using rescale::ScaleFloat;
using rescale::Store;

bool ParseDepthMapHeader(const std::string& head,
                         uint64_t file_size,
                         DepthMapLayout* layout,
                         std::string* problem) {
  // Header "W&H&C&" with positive decimal integers, as colmap::mvs::Mat
  // writes it.
  uint64_t dims[3] = {0, 0, 0};
  size_t pos = 0;
  for (int i = 0; i < 3; ++i) {
    const size_t start = pos;
    while (pos < head.size() && pos - start < 10 && head[pos] >= '0' &&
           head[pos] <= '9') {
      dims[i] = dims[i] * 10 + (head[pos] - '0');
      ++pos;
    }
    if (pos == start || pos >= head.size() || head[pos] != '&' ||
        dims[i] == 0) {
      *problem =
          "not a COLMAP depth map (bad \"width&height&channels&\" header)";
      return false;
    }
    ++pos;
  }
  // The dimensions come from the file: compare them with the data size
  // without forming a product that could overflow.
  const uint64_t data_bytes = file_size - pos;
  const uint64_t num_values = data_bytes / 4;
  const bool size_ok = data_bytes % 4 == 0 && dims[0] <= num_values &&
                       dims[1] <= num_values / dims[0] &&
                       dims[2] <= num_values / (dims[0] * dims[1]) &&
                       dims[0] * dims[1] * dims[2] == num_values;
  if (!size_ok) {
    std::ostringstream message;
    message << "size does not match its header " << dims[0] << "&" << dims[1]
            << "&" << dims[2] << "& (expected "
            << static_cast<long double>(dims[0]) * dims[1] * dims[2] * 4
            << " data bytes, found " << data_bytes << ")";
    *problem = message.str();
    return false;
  }
  layout->width = dims[0];
  layout->height = dims[1];
  layout->channels = dims[2];
  layout->data_offset = pos;
  return true;
}

bool ParseDepthMapLayout(const std::string& bytes,
                         DepthMapLayout* layout,
                         std::string* problem) {
  return ParseDepthMapHeader(bytes, bytes.size(), layout, problem);
}

void RescaleDepthMap(double scale,
                     const std::string& path,
                     std::string* contents) {
  CheckScale(scale);
  std::string& bytes = *contents;
  DepthMapLayout layout;
  std::string problem;
  if (!ParseDepthMapLayout(bytes, &layout, &problem)) {
    Corrupt(path, problem);
  }
  const size_t pos = layout.data_offset;
  const uint64_t num_values = layout.width * layout.height * layout.channels;
  // Check every value before changing any.
  for (uint64_t i = 0; i < num_values; ++i) {
    const float v = Load<float>(bytes, pos + i * 4);
    if (!std::isfinite(v)) {
      Corrupt(path, "non-finite depth value at index " + std::to_string(i));
    }
    if (v > 0.0f) ScaleFloat(v, scale, path, "depth value");
  }
  for (uint64_t i = 0; i < num_values; ++i) {
    const size_t at = pos + i * 4;
    const float v = Load<float>(bytes, at);
    if (v > 0.0f) {
      Store<float>(
          at, static_cast<float>(static_cast<double>(v) * scale), &bytes);
    }
  }
}

}  // namespace dpsfm
