// Matrix helpers the core shares.
#pragma once

#include <cstdint>
#include <cstring>
#include <functional>
#include <string_view>

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

// A hash of size, type and bytes (equal for SameBytes matrices): where a
// cache keyed by a matrix's contents looks first, before SameBytes.
inline uint64_t HashBytes(const cv::Mat& m, uint64_t seed = 0) {
  const std::hash<std::string_view> hash;
  uint64_t h = seed ^ (static_cast<uint64_t>(m.type()) << 48) ^
               (static_cast<uint64_t>(m.rows) << 24) ^
               static_cast<uint64_t>(m.cols);
  const size_t row_bytes = m.cols * m.elemSize();
  for (int y = 0; y < m.rows; ++y) {
    const std::string_view row(reinterpret_cast<const char*>(m.ptr(y)),
                               row_bytes);
    h = (h ^ hash(row)) * 1099511628211ull;  // FNV-1a's prime
  }
  return h;
}

}  // namespace dpsfm
