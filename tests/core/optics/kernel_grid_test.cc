#include "dpsfm/core/optics/kernel_grid.h"

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "dpsfm/core/optics/dp_psf.h"

namespace dpsfm {
namespace {

// True convolution of `image` with `kernel` (centred) at the pixels of
// `rect`, by the definition: sum_d kernel(d) image(x - d).
cv::Mat DirectConvolution(const cv::Mat& image,
                          const cv::Mat& kernel,
                          const cv::Rect& rect) {
  const int cy = kernel.rows / 2, cx = kernel.cols / 2;
  cv::Mat out(rect.size(), CV_64FC1);
  for (int y = 0; y < rect.height; ++y) {
    for (int x = 0; x < rect.width; ++x) {
      double sum = 0;
      for (int i = 0; i < kernel.rows; ++i) {
        for (int j = 0; j < kernel.cols; ++j) {
          sum += kernel.at<float>(i, j) *
                 image.at<float>(rect.y + y - (i - cy), rect.x + x - (j - cx));
        }
      }
      out.at<double>(y, x) = sum;
    }
  }
  return out;
}

// The grid's convolution of the patch's interior with node n's right
// kernel: the class's input spectrum times the node's, transformed back.
cv::Mat GridConvolution(const DPKernelGrid& grid,
                        const cv::Mat& patch,
                        int border,
                        int n) {
  const int c = grid.SpectrumClassOf(n);
  cv::Mat product, image;
  cv::mulSpectrums(
      grid.TransformInput(patch, border, c), grid.RightSpectrum(n), product, 0);
  cv::Mat out;
  grid.InteriorOfInverse(c, &product, &image).convertTo(out, CV_64FC1);
  return out;
}

TEST(FastDftSize, PowersOfTwoTimesFewOddFactors) {
  EXPECT_EQ(FastDftSize(1), 1);
  EXPECT_EQ(FastDftSize(7), 8);
  EXPECT_EQ(FastDftSize(26), 32);
  EXPECT_EQ(FastDftSize(33), 36);
  EXPECT_EQ(FastDftSize(45), 48);  // cv::getOptimalDFTSize: 45
  EXPECT_EQ(FastDftSize(61), 64);  // 64, not 72 or 75
  EXPECT_EQ(FastDftSize(73), 80);  // cv::getOptimalDFTSize: 75
  EXPECT_EQ(FastDftSize(81), 96);  // cv::getOptimalDFTSize: 81
  EXPECT_EQ(FastDftSize(97), 100);
  for (int n = 1; n <= 300; ++n) {
    const int size = FastDftSize(n);
    ASSERT_GE(size, n);
    int odd = size;
    while (odd % 2 == 0) odd /= 2;
    EXPECT_TRUE(odd == 1 || odd == 3 || odd == 5 || odd == 9 || odd == 25)
        << n << " -> " << size;
  }
}

// Every node's spectra convolve the interior exactly, whatever its class,
// for a patch with the grid's own border and for one with a wider border
// (the intensity stage's stored crops); nodes near focus use smaller
// transforms than nodes at the bound.
TEST(DPKernelGrid, EachClassConvolvesTheInteriorExactly) {
  const TranslatingDiskPsf psf;
  const cv::Size interior(33, 29);
  const DPKernelGrid grid(psf, 0.25, 11, interior);
  ASSERT_GT(grid.NumSpectrumClasses(), 2);
  const int zero = grid.HalfNodes();
  const int last = grid.NumNodes() - 1;
  EXPECT_LT(grid.SpectrumClassAt(grid.SpectrumClassOf(zero)).dft_size.area(),
            grid.SpectrumClassAt(grid.SpectrumClassOf(last)).dft_size.area());
  for (int n = 0; n < grid.NumNodes(); ++n) {
    const DPKernelGrid::SpectrumClass& c =
        grid.SpectrumClassAt(grid.SpectrumClassOf(n));
    EXPECT_GE(c.reach, grid.Reach(n));
    EXPECT_LE(interior.width + 2 * c.reach, c.dft_size.width);
    EXPECT_LE(interior.height + 2 * c.reach, c.dft_size.height);
    EXPECT_EQ(grid.RightSpectrum(n).size(),
              grid.Transform(grid.SpectrumClassOf(n)).SpectrumSize());
    EXPECT_EQ(grid.Transform(grid.SpectrumClassOf(n)).size(), c.dft_size);
    // The disk's views take half the light each.
    EXPECT_NEAR(grid.LeftSum(n), 0.5, 1e-5);
    EXPECT_NEAR(grid.RightSum(n), 0.5, 1e-5);
  }
  cv::RNG rng(7);
  for (const int border : {grid.Border(), grid.Border() + 9}) {
    cv::Mat patch(
        interior.height + 2 * border, interior.width + 2 * border, CV_32FC1);
    rng.fill(patch, cv::RNG::UNIFORM, 0.0, 1.0);
    const cv::Rect rect(border, border, interior.width, interior.height);
    std::vector<int> nodes;
    for (int n = 0; n < last; n += 5) nodes.push_back(n);
    nodes.push_back(last);
    for (const int n : nodes) {
      const cv::Mat expected =
          DirectConvolution(patch, grid.RightKernel(n), rect);
      const cv::Mat got = GridConvolution(grid, patch, border, n);
      ASSERT_EQ(got.size(), expected.size());
      EXPECT_LT(cv::norm(got, expected, cv::NORM_INF), 1e-5)
          << "node " << n << " (r = " << grid.Radius(n) << "), border "
          << border;
    }
  }
}

TEST(DPKernelGrid, RefusesAPatchNarrowerThanTheKernelsReach) {
  const DPKernelGrid grid(TranslatingDiskPsf(), 0.25, 6, cv::Size(20, 20));
  const int last = grid.SpectrumClassOf(grid.NumNodes() - 1);
  const int reach = grid.SpectrumClassAt(last).reach;
  const cv::Mat patch =
      cv::Mat::zeros(20 + 2 * (reach - 1), 20 + 2 * (reach - 1), CV_32FC1);
  EXPECT_THROW(grid.TransformInput(patch, reach - 1, last),
               std::invalid_argument);
}

// Tabulated on two threads, the grid is the one thread's to the bit.
TEST(DPKernelGrid, TheSameOnTwoThreads) {
  const SplitProfilePsf psf(SplitProfileParams::ForCentroidOffset(0.2));
  const DPKernelGrid one(psf, 0.25, 9, cv::Size(31, 31), 1);
  const DPKernelGrid two(psf, 0.25, 9, cv::Size(31, 31), 2);
  ASSERT_EQ(one.NumNodes(), two.NumNodes());
  ASSERT_EQ(one.NumSpectrumClasses(), two.NumSpectrumClasses());
  for (int n = 0; n < one.NumNodes(); ++n) {
    EXPECT_EQ(cv::norm(one.LeftKernel(n), two.LeftKernel(n), cv::NORM_INF), 0);
    EXPECT_EQ(
        cv::norm(one.RightSpectrum(n), two.RightSpectrum(n), cv::NORM_INF), 0);
    EXPECT_EQ(one.LeftEnergy(n), two.LeftEnergy(n));
    EXPECT_EQ(one.SpectrumClassOf(n), two.SpectrumClassOf(n));
    if (n + 1 < one.NumNodes()) {
      EXPECT_EQ(one.RightCross(n), two.RightCross(n));
    }
  }
}

// A model's kernels, rendered at every r: the same profile without
// DPPsfModel::SwapsViewsWithSign.
class EveryRadiusRendered : public DPPsfModel {
 public:
  explicit EveryRadiusRendered(const DPPsfModel& psf) : psf_(psf) {}
  std::string Name() const override { return psf_.Name(); }
  DPKernels Kernels(double r) const override { return psf_.Kernels(r); }
  int KernelRadius(double r) const override { return psf_.KernelRadius(r); }

 private:
  const DPPsfModel& psf_;
};

// A grid that takes the nodes below r = 0 from their mirrors is the grid
// that renders and transforms every node, to the bit.
TEST(DPKernelGrid, MirroredNodesAreTheRenderedOnes) {
  SplitProfileParams params = SplitProfileParams::ForCentroidOffset(0.25);
  params.crosstalk = 0.1;
  const SplitProfilePsf split(params);
  const TranslatingDiskPsf disk;
  for (const DPPsfModel* psf : std::vector<const DPPsfModel*>{&split, &disk}) {
    const EveryRadiusRendered plain(*psf);
    ASSERT_TRUE(psf->SwapsViewsWithSign());
    ASSERT_FALSE(plain.SwapsViewsWithSign());
    const DPKernelGrid mirrored(*psf, 0.25, 6.1, cv::Size(17, 17), 2);
    const DPKernelGrid rendered(plain, 0.25, 6.1, cv::Size(17, 17), 2);
    ASSERT_EQ(mirrored.NumNodes(), rendered.NumNodes());
    ASSERT_EQ(mirrored.NumSpectrumClasses(), rendered.NumSpectrumClasses());
    for (int n = 0; n < mirrored.NumNodes(); ++n) {
      const std::string at = psf->Name() + " node " + std::to_string(n);
      ASSERT_EQ(mirrored.LeftKernel(n).size(), rendered.LeftKernel(n).size())
          << at;
      EXPECT_EQ(
          cv::norm(
              mirrored.LeftKernel(n), rendered.LeftKernel(n), cv::NORM_INF),
          0)
          << at;
      EXPECT_EQ(
          cv::norm(
              mirrored.RightKernel(n), rendered.RightKernel(n), cv::NORM_INF),
          0)
          << at;
      EXPECT_EQ(
          cv::norm(
              mirrored.LeftSpectrum(n), rendered.LeftSpectrum(n), cv::NORM_INF),
          0)
          << at;
      EXPECT_EQ(cv::norm(mirrored.RightSpectrum(n),
                         rendered.RightSpectrum(n),
                         cv::NORM_INF),
                0)
          << at;
      EXPECT_EQ(mirrored.SpectrumClassOf(n), rendered.SpectrumClassOf(n)) << at;
      EXPECT_EQ(mirrored.LeftEnergy(n), rendered.LeftEnergy(n)) << at;
      EXPECT_EQ(mirrored.RightEnergy(n), rendered.RightEnergy(n)) << at;
      EXPECT_EQ(mirrored.LeftSum(n), rendered.LeftSum(n)) << at;
      EXPECT_EQ(mirrored.RightSum(n), rendered.RightSum(n)) << at;
      if (n + 1 < mirrored.NumNodes()) {
        EXPECT_EQ(mirrored.LeftCross(n), rendered.LeftCross(n)) << at;
        EXPECT_EQ(mirrored.RightCross(n), rendered.RightCross(n)) << at;
      }
    }
  }
}

// A model whose kernels are even-sized beyond 3 px.
class EvenBeyondThreePx : public DPPsfModel {
 public:
  std::string Name() const override { return "even_beyond_3px"; }
  DPKernels Kernels(double r) const override {
    const int size = std::abs(r) > 3 ? 4 : 2 * KernelRadius(r) + 1;
    DPKernels k;
    k.left = cv::Mat(size, size, CV_32FC1, cv::Scalar(0.5 / (size * size)));
    k.right = k.left.clone();
    return k;
  }
  int KernelRadius(double r) const override {
    return static_cast<int>(std::ceil(std::abs(r)));
  }
};

// A node's failure leaves the parallel tabulation as the exception it is.
TEST(DPKernelGrid, ANodesFailureIsThrownAfterTheParallelLoop) {
  EXPECT_THROW(DPKernelGrid(EvenBeyondThreePx(), 0.25, 6, cv::Size(20, 20), 2),
               std::invalid_argument);
  EXPECT_NO_THROW(
      DPKernelGrid(EvenBeyondThreePx(), 0.25, 3, cv::Size(20, 20), 2));
}

}  // namespace
}  // namespace dpsfm
