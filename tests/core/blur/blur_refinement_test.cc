// The blur search's exact refinement (core/blur/blur_search_internal.h):
// its loss at a node and its gain equalisation against spatial
// convolutions (cv::filter2D), which share nothing with its transforms.
#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "dpsfm/core/blur/blur_search_internal.h"
#include "tests/core/synthetic_dp.h"

namespace dpsfm {
namespace {

using internal::BlurRefinement;
using internal::BlurTables;

// True convolution of `image` with `kernel` (odd, centre = origin).
cv::Mat Convolve(const cv::Mat& image, const cv::Mat& kernel) {
  cv::Mat wide, flipped, out;
  image.convertTo(wide, CV_64F);
  cv::flip(kernel, flipped, -1);
  cv::filter2D(wide, out, CV_64F, flipped);
  return out;
}

// sum over the interior of the residual G_l * H_r - G_r * H_l, squared,
// over its pixel count.
double SpatialLoss(const BlurTables& t,
                   const cv::Mat& gl,
                   const cv::Mat& gr,
                   int node) {
  const cv::Mat e = Convolve(gl, t.grid->RightKernel(node))(t.interior) -
                    Convolve(gr, t.grid->LeftKernel(node))(t.interior);
  return e.dot(e) / t.num_interior;
}

// The interior sum of a view plus `offset`, blurred by `kernel`.
double BlurredInteriorSum(const BlurTables& t,
                          const cv::Mat& view,
                          double offset,
                          const cv::Mat& kernel) {
  cv::Mat positive;
  view.convertTo(positive, CV_64F, 1.0, offset);
  return cv::sum(Convolve(positive, kernel)(t.interior))[0];
}

TEST(BlurRefinement, EqualisedGainsAndLossesAgainstSpatialConvolutions) {
  const TranslatingDiskPsf psf;
  BlurEstimationOptions options;
  options.max_radius_px = 8;
  const std::unique_ptr<BlurTables> t =
      internal::MakeBlurTables(psf, options, cv::Size(71, 71), 1);
  // A textured pair at r = 4 with unequal gains, as views minus an offset.
  test::RenderOptions render;
  render.left_gain = 1.2;
  render.right_gain = 0.8;
  const cv::Mat sharp = test::MakeTexture(cv::Size(71, 71), 17);
  const test::DPPair pair = test::RenderDP(sharp, psf, 4.0, render);
  const double offset = 0.3;
  cv::Mat gl, gr;
  pair.left.convertTo(gl, CV_32F, 1.0, -offset);
  pair.right.convertTo(gr, CV_32F, 1.0, -offset);
  BlurRefinement refinement(*t, gl, gr, offset, 0.0);
  const int node = t->half_nodes + static_cast<int>(std::round(4.0 / t->step));
  ASSERT_DOUBLE_EQ(t->Radius(node), 4.0);

  // As given.
  refinement.Evaluate(node);
  const double given = SpatialLoss(*t, gl, gr, node);
  EXPECT_NEAR(refinement.RawLoss(node), given, 1e-4 * given);

  // Equalised at r = 4: each view + offset scaled by a factor, so that
  // their interior means blurred by the cross kernels agree.
  refinement.EqualiseGain(4.0);
  const cv::Mat left = refinement.Left(), right = refinement.Right();
  cv::Mat left_ratio, right_ratio;
  cv::divide(left + offset, gl + offset, left_ratio);
  cv::divide(right + offset, gr + offset, right_ratio);
  double low, high;
  cv::minMaxLoc(left_ratio, &low, &high);
  EXPECT_NEAR(low, high, 1e-5 * high);
  const double left_gain = high;
  cv::minMaxLoc(right_ratio, &low, &high);
  EXPECT_NEAR(low, high, 1e-5 * high);
  // The gains moved the views (1.2 against 0.8 before).
  EXPECT_LT(left_gain, 0.95);
  EXPECT_GT(high, 1.05);
  const double a =
      BlurredInteriorSum(*t, left, offset, t->grid->RightKernel(node));
  const double b =
      BlurredInteriorSum(*t, right, offset, t->grid->LeftKernel(node));
  EXPECT_NEAR(a / b, 1.0, 1e-5);

  // The loss of the equalised views, at the node and two others (another
  // spectrum class among them: the grid's classes group nodes by reach).
  refinement.ResetEvaluations();
  for (const int n : {node, t->half_nodes, t->num_nodes - 1}) {
    refinement.Evaluate(n);
    const double spatial = SpatialLoss(*t, left, right, n);
    // The true blur's node leaves float rounding alone (~1e-17); views
    // scaled about another offset would leave ~1e-3.
    EXPECT_NEAR(refinement.RawLoss(n), spatial, 1e-4 * spatial + 1e-12)
        << "node " << n;
  }
  EXPECT_GT(t->grid->NumSpectrumClasses(), 1);
}

}  // namespace
}  // namespace dpsfm
