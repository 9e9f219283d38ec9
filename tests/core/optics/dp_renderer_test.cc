// The DP forward model used by the examples and benchmarks: light is
// conserved per channel, and a continuous surface stays seamless.
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "dpsfm/core/optics/dp_psf.h"
#include "dpsfm/core/optics/dp_renderer.h"

namespace dpsfm {
namespace {

// A flat colour image on a surface whose blur grows across the frame (a
// slanted plane): left + right must reproduce the colour everywhere away
// from the frame border, in every channel.
void ExpectSeamless(DPRenderOptions::Compositing compositing,
                    double max_error) {
  const cv::Size size(240, 120);
  const cv::Mat sharp(size, CV_32FC3, cv::Scalar(0.2, 0.5, 0.8));
  cv::Mat depth(size, CV_32FC1), radius(size, CV_32FC1);
  for (int r = 0; r < size.height; ++r) {
    for (int c = 0; c < size.width; ++c) {
      depth.at<float>(r, c) = 1.0f + 0.01f * c;
      radius.at<float>(r, c) = -4.0f + 0.03f * c;
    }
  }
  DPRenderOptions options;
  options.compositing = compositing;
  cv::Mat left, right;
  RenderDPViews(
      sharp, depth, radius, TranslatingDiskPsf(), options, &left, &right);
  ASSERT_EQ(left.type(), CV_32FC3);
  const cv::Mat sum = left + right;
  double worst = 0;
  for (int r = 10; r < size.height - 10; ++r) {
    for (int c = 10; c < size.width - 10; ++c) {
      const cv::Vec3f value = sum.at<cv::Vec3f>(r, c);
      worst = std::max({worst,
                        std::abs(value[0] - 0.2),
                        std::abs(value[1] - 0.5),
                        std::abs(value[2] - 0.8)});
    }
  }
  EXPECT_LT(worst, max_error);
}

TEST(RenderDPViews, AdditiveIsSeamlessOnASlantedSurface) {
  // Hard bins left lines of +-10 % at every bin edge; interpolated bins
  // leave only the PSF's own step where |r| crosses the in-focus threshold
  // (about 1.5 % here).
  ExpectSeamless(DPRenderOptions::Compositing::kAdditive, 0.015);
}

TEST(RenderDPViews, LayersKeepEveryColourChannel) {
  // "Over" compositing seams a continuous surface at bin edges (documented),
  // but every channel must still carry the scene.
  ExpectSeamless(DPRenderOptions::Compositing::kOcclusionLayers, 0.25);
}

TEST(RenderDPViews, EachViewGetsHalfTheLight) {
  const cv::Mat sharp(64, 64, CV_32FC1, cv::Scalar(0.6));
  const cv::Mat depth(64, 64, CV_32FC1, cv::Scalar(2.0));
  const cv::Mat radius(64, 64, CV_32FC1, cv::Scalar(3.0));
  cv::Mat left, right;
  RenderDPViews(sharp,
                depth,
                radius,
                TranslatingDiskPsf(),
                DPRenderOptions(),
                &left,
                &right);
  EXPECT_NEAR(left.at<float>(32, 32), 0.3, 1e-4);
  EXPECT_NEAR(right.at<float>(32, 32), 0.3, 1e-4);
}

}  // namespace
}  // namespace dpsfm
