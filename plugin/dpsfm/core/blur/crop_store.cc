#include "dpsfm/core/blur/crop_store.h"

#include <algorithm>

#include <opencv2/core.hpp>

#include "dpsfm/core/blur/patch_grid.h"

namespace dpsfm {
namespace {

cv::Mat ToU16(const cv::Mat& image) {
  cv::Mat out;
  image.convertTo(out, CV_MAKETYPE(CV_16U, image.channels()), 65535.0);
  return out;
}

}  // namespace

int MaxStoredCrops(int crop,
                   int channels,
                   int max_count,
                   double max_megabytes) {
  const double crop_bytes = 2.0 * crop * crop * channels * 2;
  const int by_memory = static_cast<int>(max_megabytes * 1e6 / crop_bytes);
  return std::max(0, std::min(max_count, by_memory));
}

std::vector<StoredCrop> StoreCrops(
    const cv::Mat& left,
    const cv::Mat& right,
    const std::vector<std::pair<int, cv::Rect>>& sample_interiors,
    int border,
    int store_border) {
  std::vector<StoredCrop> stored;
  if (sample_interiors.empty()) return stored;
  const int pad = store_border - border;
  cv::Mat padded_left = left, padded_right = right;
  if (pad > 0) {
    cv::copyMakeBorder(
        left, padded_left, pad, pad, pad, pad, cv::BORDER_REFLECT_101);
    cv::copyMakeBorder(
        right, padded_right, pad, pad, pad, pad, cv::BORDER_REFLECT_101);
  }
  for (const auto& sample_interior : sample_interiors) {
    const cv::Rect& interior = sample_interior.second;
    // In padded coordinates the interior moved by pad.
    const cv::Rect r = PatchCrop(interior + cv::Point(pad, pad), store_border);
    StoredCrop crop;
    crop.sample = sample_interior.first;
    crop.left = ToU16(padded_left(r));
    crop.right = ToU16(padded_right(r));
    crop.border = store_border;
    stored.push_back(crop);
  }
  return stored;
}

}  // namespace dpsfm
