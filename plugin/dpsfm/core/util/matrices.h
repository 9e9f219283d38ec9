// Matrix helpers the core shares.
#pragma once

#include <cstring>

#include <opencv2/core.hpp>

namespace dpsfm {

// Same size, type and bytes: what caches keyed by a matrix's contents need
// (cv::norm compares values, so -0 equals +0 and a NaN nothing).
inline bool SameBytes(const cv::Mat& a, const cv::Mat& b) {
  if (a.size() != b.size() || a.type() != b.type()) return false;
  const size_t row_bytes = a.cols * a.elemSize();
  for (int y = 0; y < a.rows; ++y) {
    if (std::memcmp(a.ptr(y), b.ptr(y), row_bytes) != 0) return false;
  }
  return true;
}

}  // namespace dpsfm
