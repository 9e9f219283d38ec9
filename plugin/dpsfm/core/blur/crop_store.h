// The crop store (the last step of DPScaleEstimator::AddView): 16-bit crops
// of a view's best patches, all the later stages keep of its frames, so
// memory per view is bounded (by count and megabytes) whatever its size.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace dpsfm {

struct StoredCrop {
  int sample = -1;      // index of the view's PatchSample
  // CV_16UC1/3 crops with border; views into one region of the frames
  // that a view's crops share when it is smaller than they are (StoreCrops).
  cv::Mat left, right;
  int border = 0;       // px around the patch interior
};

// How many crops of a `crop` px square with `channels` channels (two views,
// 16 bit) fit in max_megabytes, and at most max_count.
int MaxStoredCrops(int crop, int channels, int max_count, double max_megabytes);

// Crops of the working frames around each (sample, interior) with
// `store_border` px of border. The frames carry `border` px around every
// interior; a wider store border is reached by reflecting the frames
// (BORDER_REFLECT_101), so wide crops near the edges exist too. The crops
// share one copy of the frames' region around them (their bounding box)
// when it is smaller than they are: they are then views into it, not
// continuous, and keep it alive while any of them is held.
std::vector<StoredCrop> StoreCrops(
    const cv::Mat& left,
    const cv::Mat& right,
    const std::vector<std::pair<int, cv::Rect>>& sample_interiors,
    int border,
    int store_border);

}  // namespace dpsfm
