// The DP forward model used by the examples and benchmarks: light is
// conserved per channel, and a continuous surface stays seamless.
#include <algorithm>
#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "dpsfm/core/optics/dp_psf.h"
#include "dpsfm/core/optics/dp_renderer.h"

namespace dpsfm {
namespace {

const cv::Vec3f kColour(0.2f, 0.5f, 0.8f);

// left + right of a flat colour image on a surface whose blur radius is
// radius_at(column), and where it is compared (away from the frame border).
struct Rendered {
  cv::Mat sum;
  cv::Rect interior;
};

template <typename RadiusAt>
Rendered RenderFlatColour(DPRenderOptions::Compositing compositing,
                          RadiusAt radius_at) {
  const cv::Size size(240, 120);
  const cv::Mat sharp(size, CV_32FC3, cv::Scalar(kColour));
  cv::Mat depth(size, CV_32FC1), radius(size, CV_32FC1);
  for (int r = 0; r < size.height; ++r) {
    for (int c = 0; c < size.width; ++c) {
      depth.at<float>(r, c) = 1.0f + 0.01f * c;
      radius.at<float>(r, c) = radius_at(c);
    }
  }
  DPRenderOptions options;
  options.compositing = compositing;
  cv::Mat left, right;
  RenderDPViews(
      sharp, depth, radius, TranslatingDiskPsf(), options, &left, &right);
  EXPECT_EQ(left.type(), CV_32FC3);
  EXPECT_EQ(right.type(), CV_32FC3);
  return Rendered{left + right, cv::Rect(10, 10, 220, 100)};
}

// Every channel of the sum against its own colour value, relative to it (so
// a zeroed or exchanged channel is off by 37.5 % or more), and the channels
// against each other: the renderer weights, blurs and composites every
// channel with the same single-channel masks and kernels, so whatever it
// does to the light (seams included) it does to all channels alike, and
// sum_c / colour_c is one number per pixel.
void ExpectColourKept(const Rendered& rendered, double max_relative_error) {
  ASSERT_EQ(rendered.sum.type(), CV_32FC3);
  double worst[3] = {0, 0, 0};
  double worst_spread = 0;
  for (int r = rendered.interior.y; r < rendered.interior.br().y; ++r) {
    for (int c = rendered.interior.x; c < rendered.interior.br().x; ++c) {
      const cv::Vec3f value = rendered.sum.at<cv::Vec3f>(r, c);
      double lo = 1e30, hi = -1e30;
      for (int ch = 0; ch < 3; ++ch) {
        const double ratio = value[ch] / kColour[ch];
        worst[ch] = std::max(worst[ch], std::abs(ratio - 1));
        lo = std::min(lo, ratio);
        hi = std::max(hi, ratio);
      }
      worst_spread = std::max(worst_spread, hi - lo);
    }
  }
  for (int ch = 0; ch < 3; ++ch) {
    EXPECT_LT(worst[ch], max_relative_error)
        << "channel " << ch << " (" << kColour[ch] << ")";
  }
  EXPECT_LT(worst_spread, 1e-4) << "channels treated differently";
}

// A slanted plane: the blur grows across the frame through many bins.
float Slanted(int column) { return -4.0f + 0.03f * column; }

TEST(RenderDPViews, AdditiveIsSeamlessOnASlantedSurface) {
  // Hard bins left lines of +-10 % at every bin edge; interpolated bins
  // leave only the PSF's own step where |r| crosses the in-focus threshold
  // (about 1.5 % here).
  ExpectColourKept(
      RenderFlatColour(DPRenderOptions::Compositing::kAdditive, Slanted), 0.02);
}

TEST(RenderDPViews, LayersKeepEveryColourChannel) {
  // "Over" compositing seams a continuous surface at bin edges (documented:
  // each bin's soft edge partly hides its neighbour, up to ~19 % dark here),
  // but every channel must still carry the scene.
  ExpectColourKept(
      RenderFlatColour(DPRenderOptions::Compositing::kOcclusionLayers, Slanted),
      0.2);
}

TEST(RenderDPViews, FlatFieldKeepsItsColourInOneBin) {
  // One radius, so no bin edges: blurring a flat field keeps its value in
  // either mode (a radius between two bins splits the light between them
  // in the additive mode), to float precision (measured ~1e-7).
  for (const float radius : {-3.0f, 2.6f}) {
    for (const auto compositing :
         {DPRenderOptions::Compositing::kAdditive,
          DPRenderOptions::Compositing::kOcclusionLayers}) {
      SCOPED_TRACE(::testing::Message() << "r = " << radius << ", mode "
                                        << static_cast<int>(compositing));
      ExpectColourKept(
          RenderFlatColour(compositing, [radius](int) { return radius; }),
          1e-3);
    }
  }
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
