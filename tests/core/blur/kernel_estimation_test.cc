#include "dpsfm/core/blur/kernel_estimation.h"

#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "tests/core/synthetic_dp.h"

namespace dpsfm {
namespace {

cv::Mat Normalised(const cv::Mat& k) { return k / cv::sum(k)[0]; }

// Sum of |a - b| of two kernels normalised to one, centre-aligned (the
// smaller is zero-padded).
double L1Distance(const cv::Mat& a, const cv::Mat& b) {
  const int size = std::max(a.rows, b.rows);
  auto pad = [&](const cv::Mat& k) {
    cv::Mat out;
    const int p = (size - k.rows) / 2;
    cv::copyMakeBorder(Normalised(k), out, p, p, p, p, cv::BORDER_CONSTANT, 0);
    return out;
  };
  return cv::norm(pad(a), pad(b), cv::NORM_L1);
}

double SeparationX(const DPKernels& k) {
  return KernelCentroid(k.right).x - KernelCentroid(k.left).x;
}

cv::Mat Texture(int seed) {
  return test::MakeTexture(cv::Size(200, 160), seed);
}

cv::Mat AddNoise(const cv::Mat& image, double sigma, int seed) {
  cv::Mat noise(image.size(), CV_32FC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0, sigma);
  return image + noise;
}

}  // namespace

// Noise-free: an elliptical, rotated soft-split kernel pair (outside every
// family the estimator fits) comes back to within a few per cent of its
// light, with its disparity.
TEST(EstimateKernel, RecoversAnOutOfFamilyKernelWithoutNoise) {
  const test::KernelPair truth = test::SoftSplitKernels(4, 0.75, 16, 3.0);
  const cv::Mat sharp = Texture(1);
  KernelEstimationOptions options;
  options.half_size = 6;
  options.smoothness = 1e-4;
  const EstimatedKernel left = EstimateKernel(
      sharp, test::ConvolveWithOpenCV(sharp, truth.left), options);
  const EstimatedKernel right = EstimateKernel(
      sharp, test::ConvolveWithOpenCV(sharp, truth.right), options);
  const double dl = L1Distance(left.kernel, truth.left);
  const double dr = L1Distance(right.kernel, truth.right);
  std::printf("L1 %.4f %.4f, residual %.2e, %d iterations\n",
              dl,
              dr,
              left.relative_residual,
              left.iterations);
  EXPECT_LT(dl, 0.05);
  EXPECT_LT(dr, 0.05);
  EXPECT_LT(left.relative_residual, 0.02);
  // The light ratio of blurred to sharp is the kernel's sum.
  EXPECT_NEAR(cv::sum(left.kernel)[0] / cv::sum(truth.left)[0], 1.0, 0.03);
}

// With the noise of a real capture (0.3 % of the range in each image), the
// pair's shape and its left/right separation survive; the stopped-down
// capture misregistered by (2, -1) px is re-centred away.
TEST(EstimateDPKernels, NoisyMisregisteredCaptureKeepsShapeAndDisparity) {
  const test::KernelPair truth =
      test::SoftSplitKernels(4, 0.8, -20, 2.0, 0, 1.5);
  const cv::Mat scene = test::MakeTexture(cv::Size(240, 200), 7);
  const cv::Mat left =
      AddNoise(test::ConvolveWithOpenCV(scene, truth.left), 0.003, 1);
  const cv::Mat right =
      AddNoise(test::ConvolveWithOpenCV(scene, truth.right), 0.003, 2);
  // The sharp capture: the scene 2 px to the right and 1 px up, darker
  // (a stopped-down exposure), with its own noise.
  cv::Mat moved;
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, 2, 0, 1, -1);
  cv::warpAffine(
      scene, moved, shift, scene.size(), cv::INTER_NEAREST, cv::BORDER_REFLECT);
  const cv::Mat sharp = AddNoise(0.4 * moved, 0.003, 3);
  KernelEstimationOptions options;
  options.half_size = 8;
  const EstimatedDPKernels k = EstimateDPKernels(sharp, left, right, options);
  DPKernels t;
  t.left = Normalised(truth.left) * 0.5;
  t.right = Normalised(truth.right) * 0.5;
  const double dl = L1Distance(k.kernels.left, t.left);
  const double dr = L1Distance(k.kernels.right, t.right);
  std::printf(
      "L1 %.3f %.3f, separation %.3f (truth %.3f), moved by (%.2f, "
      "%.2f), left share %.3f\n",
      dl,
      dr,
      SeparationX(k.kernels),
      SeparationX(t),
      k.recentred_by.x,
      k.recentred_by.y,
      k.left_share);
  EXPECT_LT(dl, 0.18);
  EXPECT_LT(dr, 0.18);
  EXPECT_NEAR(SeparationX(k.kernels) / SeparationX(t), 1.0, 0.06);
  // The blurred views are the sharp one moved back by (-2, +1).
  EXPECT_NEAR(k.recentred_by.x, -2, 0.15);
  EXPECT_NEAR(k.recentred_by.y, 1, 0.15);
  EXPECT_NEAR(k.left_share, 0.5, 0.01);
  EXPECT_NEAR(cv::sum(k.kernels.left)[0], 0.5, 1e-5);
  EXPECT_NEAR(cv::sum(k.kernels.right)[0], 0.5, 1e-5);
}

TEST(ShiftKernel, BilinearAgainstTheClosedForm) {
  cv::Mat delta = cv::Mat::zeros(5, 5, CV_32FC1);
  delta.at<float>(2, 2) = 2;
  const cv::Mat moved = ShiftKernel(delta, 0.25, -1);
  EXPECT_NEAR(moved.at<float>(1, 2), 1.5, 1e-6);
  EXPECT_NEAR(moved.at<float>(1, 3), 0.5, 1e-6);
  EXPECT_NEAR(cv::sum(moved)[0], 2, 1e-6);
  EXPECT_NEAR(KernelCentroid(moved).x, 0.25, 1e-6);
  EXPECT_NEAR(KernelCentroid(moved).y, -1, 1e-6);
}

TEST(EstimateKernel, RefusesWhatCannotBeMeasured) {
  const cv::Mat flat(100, 100, CV_32FC1, cv::Scalar(0.5));
  KernelEstimationOptions options;
  EXPECT_THROW(EstimateKernel(flat, flat, options), std::invalid_argument);
  const cv::Mat small = Texture(3)(cv::Rect(0, 0, 30, 30));
  EXPECT_THROW(EstimateKernel(small, small, options), std::invalid_argument);
  options.half_size = 0;
  EXPECT_FALSE(options.Check());
}

}  // namespace dpsfm
