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
  std::vector<cv::Rect> rects;  // in padded coordinates
  for (const auto& sample_interior : sample_interiors) {
    rects.push_back(
        PatchCrop(sample_interior.second + cv::Point(pad, pad), store_border));
  }
  // Crops of neighbouring patches overlap (a view's 160 crops of 111 px
  // cover 2.0 million px of a 1.5 million px working frame), so they share
  // one 16-bit copy of the region around them when that is smaller than
  // the crops one by one, each crop a view into it (not continuous). The
  // values are the same either way: the conversion is per element.
  cv::Rect region = rects.front();
  double crops_area = 0;
  for (const cv::Rect& r : rects) {
    region |= r;
    crops_area += r.area();
  }
  cv::Mat shared_left, shared_right;
  if (region.area() < crops_area) {
    shared_left = ToU16(padded_left(region));
    shared_right = ToU16(padded_right(region));
  }
  for (size_t k = 0; k < rects.size(); ++k) {
    StoredCrop crop;
    crop.sample = sample_interiors[k].first;
    if (shared_left.empty()) {
      crop.left = ToU16(padded_left(rects[k]));
      crop.right = ToU16(padded_right(rects[k]));
    } else {
      crop.left = shared_left(rects[k] - region.tl());
      crop.right = shared_right(rects[k] - region.tl());
    }
    crop.border = store_border;
    stored.push_back(crop);
  }
  return stored;
}

}  // namespace dpsfm
