// The blur search's exact refinement (core/blur/blur_search_internal.h):
// its loss at a node and its gain equalisation against spatial
// convolutions (cv::filter2D), which share nothing with its transforms.
#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "dpsfm/core/blur/blur_search_internal.h"
#include "dpsfm/core/util/matrices.h"
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

// The tables of the translating disk for 71 px patches to |r| <= 8.
std::unique_ptr<BlurTables> DiskTables() {
  BlurEstimationOptions options;
  options.max_radius_px = 8;
  return internal::MakeBlurTables(
      TranslatingDiskPsf(), options, cv::Size(71, 71), 1);
}

// A textured pair at `radius` with unequal gains, as views minus `offset`.
struct Views {
  cv::Mat gl, gr;
};
Views RenderViews(double radius,
                  double left_gain,
                  double right_gain,
                  int seed,
                  double offset) {
  test::RenderOptions render;
  render.left_gain = left_gain;
  render.right_gain = right_gain;
  const test::DPPair pair =
      test::RenderDP(test::MakeTexture(cv::Size(71, 71), seed),
                     TranslatingDiskPsf(),
                     radius,
                     render);
  Views views;
  pair.left.convertTo(views.gl, CV_32F, 1.0, -offset);
  pair.right.convertTo(views.gr, CV_32F, 1.0, -offset);
  return views;
}

TEST(BlurRefinement, EqualisedGainsAndLossesAgainstSpatialConvolutions) {
  const std::unique_ptr<BlurTables> t = DiskTables();
  const double offset = 0.3;
  const Views views = RenderViews(4.0, 1.2, 0.8, 17, offset);
  const cv::Mat& gl = views.gl;
  const cv::Mat& gr = views.gr;
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

// A prepared patch hands its integral images to every search of it: the
// equalisation they give must be the one the refinement makes itself, to
// the bit, before and after the gains first move.
TEST(BlurRefinement, GivenIntegralsEqualiseAsTakenOnes) {
  const std::unique_ptr<BlurTables> t = DiskTables();
  const double offset = 0.25;
  const Views views = RenderViews(-3.0, 1.15, 0.9, 5, offset);
  const cv::Mat& gl = views.gl;
  const cv::Mat& gr = views.gr;
  BlurRefinement taken(*t, gl, gr, offset, 0.0);
  BlurRefinement given(*t,
                       gl,
                       gr,
                       offset,
                       0.0,
                       BlurRefinement::PositiveIntegral(gl, offset),
                       BlurRefinement::PositiveIntegral(gr, offset));
  for (const double radius : {-3.0, -2.5, -3.25}) {
    taken.EqualiseGain(radius);
    given.EqualiseGain(radius);
    ASSERT_TRUE(SameBytes(taken.Left(), given.Left())) << radius;
    ASSERT_TRUE(SameBytes(taken.Right(), given.Right())) << radius;
  }
  // The gains moved (else the test shows nothing).
  EXPECT_FALSE(SameBytes(taken.Left(), gl));
  const int node = t->half_nodes - 12;
  taken.Evaluate(node);
  given.Evaluate(node);
  EXPECT_EQ(taken.RawLoss(node), given.RawLoss(node));
}

}  // namespace
}  // namespace dpsfm
