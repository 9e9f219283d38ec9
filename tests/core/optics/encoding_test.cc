#include "dpsfm/core/optics/encoding.h"

#include <stdexcept>

#include <gtest/gtest.h>

namespace dpsfm {
namespace {

// IEC 61966-2-1 by hand: 0.5 -> (0.555 / 1.055)^2.4 = 0.2140411; the linear
// toe 0.04 -> 0.04 / 12.92 = 0.0030960; both branches meet at 0.04045
// (0.0031308); 0 and 1 stay.
TEST(SrgbToLinear, StandardCurve) {
  EXPECT_NEAR(SrgbToLinear(0.5), 0.2140411405, 1e-9);
  EXPECT_NEAR(SrgbToLinear(0.04), 0.0030959752, 1e-9);
  EXPECT_NEAR(SrgbToLinear(0.04045), 0.0031308050, 1e-9);
  EXPECT_NEAR(SrgbToLinear(0.0404501), 0.0031308050, 1e-7);
  EXPECT_EQ(SrgbToLinear(0), 0);
  EXPECT_NEAR(SrgbToLinear(1), 1, 1e-12);
  // 8-bit code 128.
  EXPECT_NEAR(SrgbToLinear(128.0 / 255), 0.2158605001, 1e-9);
}

TEST(DecodeToLinearLight, EveryChannelAndOnlyForSrgb) {
  cv::Mat image(2, 3, CV_32FC3, cv::Scalar(0.5, 0.04, 1.0));
  cv::Mat linear = image.clone();
  DecodeToLinearLight(DPEncoding::kLinear, &linear);
  EXPECT_EQ(cv::norm(linear, image, cv::NORM_INF), 0);
  DecodeToLinearLight(DPEncoding::kSrgb, &image);
  for (int r = 0; r < 2; ++r) {
    for (int c = 0; c < 3; ++c) {
      const cv::Vec3f v = image.at<cv::Vec3f>(r, c);
      EXPECT_NEAR(v[0], 0.2140411, 1e-6);
      EXPECT_NEAR(v[1], 0.0030960, 1e-6);
      EXPECT_NEAR(v[2], 1.0, 1e-6);
    }
  }
  // A view into a larger image: only its pixels change.
  cv::Mat grey(4, 4, CV_32FC1, cv::Scalar(0.5));
  cv::Mat corner = grey(cv::Rect(0, 0, 2, 2));
  DecodeToLinearLight(DPEncoding::kSrgb, &corner);
  EXPECT_NEAR(grey.at<float>(1, 1), 0.2140411, 1e-6);
  EXPECT_EQ(grey.at<float>(3, 3), 0.5f);
  EXPECT_THROW(DecodeToLinearLight(DPEncoding::kAuto, &grey),
               std::invalid_argument);
}

TEST(DPEncoding, NamesRoundTrip) {
  for (const DPEncoding e :
       {DPEncoding::kAuto, DPEncoding::kLinear, DPEncoding::kSrgb}) {
    EXPECT_EQ(ParseDPEncoding(DPEncodingName(e)), e);
  }
  EXPECT_THROW(ParseDPEncoding("gamma"), std::invalid_argument);
}

}  // namespace
}  // namespace dpsfm
