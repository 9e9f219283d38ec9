// SameBytes: the caches' identity check and several tests' oracle, tested
// against what it claims (size, type and bytes; not values).
#include <cmath>
#include <limits>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "dpsfm/core/util/matrices.h"

namespace dpsfm {
namespace {

TEST(SameBytes, EqualMatricesAndTheirViews) {
  cv::Mat a(5, 7, CV_32FC1);
  cv::randu(a, -1, 1);
  EXPECT_TRUE(SameBytes(a, a));
  EXPECT_TRUE(SameBytes(a, a.clone()));
  // A view into a larger matrix (rows not contiguous) compares by its rows.
  cv::Mat big(9, 11, CV_32FC1, cv::Scalar(3));
  a.copyTo(big(cv::Rect(2, 1, 7, 5)));
  EXPECT_TRUE(SameBytes(big(cv::Rect(2, 1, 7, 5)), a));
  EXPECT_TRUE(SameBytes(cv::Mat(), cv::Mat()));
}

TEST(SameBytes, AnyDifferenceOfSizeTypeOrOneByte) {
  cv::Mat a(4, 4, CV_32FC1, cv::Scalar(0.5));
  EXPECT_FALSE(SameBytes(a, cv::Mat(4, 3, CV_32FC1, cv::Scalar(0.5))));
  cv::Mat as_double;
  a.convertTo(as_double, CV_64F);
  EXPECT_FALSE(SameBytes(a, as_double));
  // Same bytes, another type: 16 bytes of CV_8UC1 4 x 16 are not 4 x 4 floats.
  EXPECT_FALSE(SameBytes(a, cv::Mat(4, 16, CV_8UC1, a.data)));
  for (int i = 0; i < 16; ++i) {
    cv::Mat b = a.clone();
    b.ptr<uchar>(i / 4)[4 * (i % 4) + 3] ^= 0x01;  // one bit of one float
    EXPECT_FALSE(SameBytes(a, b)) << i;
  }
}

// Bytes, not values: -0 and +0 differ, a NaN equals itself (cv::norm says
// the opposite of both).
TEST(SameBytes, BytesNotValues) {
  cv::Mat plus(1, 1, CV_32FC1, cv::Scalar(0.0));
  cv::Mat minus(1, 1, CV_32FC1, cv::Scalar(-0.0));
  EXPECT_EQ(cv::norm(plus, minus, cv::NORM_INF), 0);
  EXPECT_FALSE(SameBytes(plus, minus));
  cv::Mat nan(1, 1, CV_32FC1,
              cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  EXPECT_TRUE(SameBytes(nan, nan.clone()));
}

}  // namespace
}  // namespace dpsfm
