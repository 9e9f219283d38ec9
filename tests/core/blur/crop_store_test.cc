// The crop store (core/blur/crop_store.h): its memory arithmetic by hand, and
// the stored 16-bit crops against the frames they were cut from.
#include "dpsfm/core/blur/crop_store.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace dpsfm {
namespace {

// A crop holds two views of crop^2 pixels, `channels` channels, 2 bytes each.
TEST(MaxStoredCrops, ArithmeticByHand) {
  // 111 px, RGB: 2 x 111^2 x 3 x 2 = 147852 bytes; 64 MB / 147852 = 432.9.
  EXPECT_EQ(MaxStoredCrops(111, 3, 1000, 64), 432);
  // The count caps it.
  EXPECT_EQ(MaxStoredCrops(111, 3, 100, 64), 100);
  // Grey: 49284 bytes, 64e6 / 49284 = 1298.6.
  EXPECT_EQ(MaxStoredCrops(111, 1, 5000, 64), 1298);
  // 50 px grey: 2 x 2500 x 2 = 10000 bytes; 1 MB holds exactly 100, 0.999 MB
  // 99.
  EXPECT_EQ(MaxStoredCrops(50, 1, 1000, 1.0), 100);
  EXPECT_EQ(MaxStoredCrops(50, 1, 1000, 0.999), 99);
  // Nothing fits, or nothing is allowed.
  EXPECT_EQ(MaxStoredCrops(50, 1, 1000, 0.0), 0);
  EXPECT_EQ(MaxStoredCrops(50, 1, -3, 1.0), 0);
}

// A frame of distinct values in [0, 1]: `seed` makes left and right differ.
cv::Mat Frame(const cv::Size& size, int channels, int seed) {
  cv::Mat frame(size, CV_32FC(channels));
  for (int y = 0; y < size.height; ++y) {
    float* row = frame.ptr<float>(y);
    for (int x = 0; x < size.width; ++x) {
      for (int c = 0; c < channels; ++c) {
        row[x * channels + c] =
            static_cast<float>((7 * x + 13 * y + 31 * c + seed) % 101) / 100;
      }
    }
  }
  return frame;
}

// BORDER_REFLECT_101 by hand: -1 -> 1, -2 -> 2; n -> n - 2, n + 1 -> n - 3.
int Reflect101(int i, int n) {
  if (i < 0) return -i;
  if (i >= n) return 2 * (n - 1) - i;
  return i;
}

// Every pixel of a stored crop (16 bit) against the frame pixel it comes
// from: interior at `interior`, `store_border` px around it, reflected
// outside the frame.
void ExpectCropOfFrame(const cv::Mat& crop,
                       const cv::Mat& frame,
                       const cv::Rect& interior,
                       int store_border,
                       const char* what) {
  const int channels = frame.channels();
  ASSERT_EQ(crop.type(), CV_MAKETYPE(CV_16U, channels)) << what;
  ASSERT_EQ(crop.size(),
            cv::Size(interior.width + 2 * store_border,
                     interior.height + 2 * store_border))
      << what;
  double worst = 0;
  for (int i = 0; i < crop.rows; ++i) {
    for (int j = 0; j < crop.cols; ++j) {
      const int y = Reflect101(interior.y - store_border + i, frame.rows);
      const int x = Reflect101(interior.x - store_border + j, frame.cols);
      for (int c = 0; c < channels; ++c) {
        const double stored = crop.ptr<uint16_t>(i)[j * channels + c] / 65535.0;
        const double source = frame.ptr<float>(y)[x * channels + c];
        worst = std::max(worst, std::abs(stored - source));
      }
    }
  }
  EXPECT_LE(worst, 1.0 / 65535) << what;
}

TEST(StoreCrops, RoundTripKeepsTheBorder) {
  for (const int channels : {1, 3}) {
    const cv::Mat left = Frame(cv::Size(40, 30), channels, 0);
    const cv::Mat right = Frame(cv::Size(40, 30), channels, 50);
    // Interiors of 10 px with the frame's border of 4 around them, one in
    // the middle and one in the top-left corner.
    const std::vector<std::pair<int, cv::Rect>> interiors = {
        {7, cv::Rect(15, 10, 10, 10)}, {2, cv::Rect(4, 4, 10, 10)}};
    // A store border equal to the frame's: plain crops.
    const std::vector<StoredCrop> plain =
        StoreCrops(left, right, interiors, 4, 4);
    ASSERT_EQ(plain.size(), 2u);
    // A wider one: 3 px beyond the frame at the corner, reflected.
    const std::vector<StoredCrop> wide =
        StoreCrops(left, right, interiors, 4, 7);
    ASSERT_EQ(wide.size(), 2u);
    for (size_t k = 0; k < interiors.size(); ++k) {
      const cv::Rect& interior = interiors[k].second;
      for (const auto& run :
           {std::make_pair(&plain[k], 4), std::make_pair(&wide[k], 7)}) {
        const StoredCrop& crop = *run.first;
        EXPECT_EQ(crop.sample, interiors[k].first);
        EXPECT_EQ(crop.border, run.second);
        ExpectCropOfFrame(crop.left, left, interior, run.second, "left");
        ExpectCropOfFrame(crop.right, right, interior, run.second, "right");
      }
    }
    // Apart (their bounding box of 29 x 24 px over two crops of 18 x 18):
    // each crop its own buffer.
    EXPECT_TRUE(plain[0].left.isContinuous());
    EXPECT_NE(plain[0].left.datastart, plain[1].left.datastart);
    EXPECT_NE(plain[0].right.datastart, plain[1].right.datastart);
    // Overlapping (35 x 30 px over two of 24 x 24): views into one region.
    EXPECT_FALSE(wide[0].left.isContinuous());
    EXPECT_EQ(wide[0].left.datastart, wide[1].left.datastart);
    EXPECT_EQ(wide[0].right.datastart, wide[1].right.datastart);
    EXPECT_NE(wide[0].left.datastart, wide[0].right.datastart);
  }
  // A view's crops on a patch grid (stride 8 under crops of 18 px, as the
  // searches' patches overlap): the store holds the region they cover,
  // 42 x 34 px, against 12 crops of 18 x 18 one by one.
  const cv::Mat left = Frame(cv::Size(60, 50), 3, 0);
  const cv::Mat right = Frame(cv::Size(60, 50), 3, 50);
  std::vector<std::pair<int, cv::Rect>> grid;
  for (int y = 4; y <= 20; y += 8) {
    for (int x = 4; x <= 28; x += 8) {
      grid.emplace_back(static_cast<int>(grid.size()), cv::Rect(x, y, 10, 10));
    }
  }
  const std::vector<StoredCrop> stored = StoreCrops(left, right, grid, 4, 4);
  ASSERT_EQ(stored.size(), grid.size());
  std::set<const uchar*> buffers;
  for (size_t k = 0; k < grid.size(); ++k) {
    ExpectCropOfFrame(stored[k].left, left, grid[k].second, 4, "left");
    ExpectCropOfFrame(stored[k].right, right, grid[k].second, 4, "right");
    buffers.insert(stored[k].left.datastart);
    buffers.insert(stored[k].right.datastart);
    EXPECT_EQ(stored[k].left.dataend - stored[k].left.datastart,
              42 * 34 * 3 * 2);
  }
  EXPECT_EQ(buffers.size(), 2u);
  EXPECT_TRUE(
      StoreCrops(
          Frame(cv::Size(8, 8), 1, 0), Frame(cv::Size(8, 8), 1, 1), {}, 2, 2)
          .empty());
}

}  // namespace
}  // namespace dpsfm
