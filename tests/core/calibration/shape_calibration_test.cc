#include "dpsfm/core/calibration/shape_calibration.h"

#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "tests/core/synthetic_dp.h"

namespace dpsfm {
namespace {

cv::Mat Noisy(const cv::Mat& image, int seed) {
  cv::Mat noise(image.size(), CV_32FC1);
  cv::RNG(seed).fill(noise, cv::RNG::NORMAL, 0, 0.003);
  return image + noise;
}

// The truth's centroid offset per radius, from the kernels' pixels.
double Offset(const test::KernelPair& k, double radius) {
  auto cx = [](const cv::Mat& m) {
    double s = 0, w = 0;
    for (int y = 0; y < m.rows; ++y) {
      for (int x = 0; x < m.cols; ++x) {
        s += (x - m.cols / 2) * m.at<float>(y, x);
        w += m.at<float>(y, x);
      }
    }
    return s / w;
  };
  return (cx(k.right) - cx(k.left)) / (2 * radius);
}

// The pair shifted (bilinear, OpenCV's warpAffine) so that the centroid of
// its views' sum is the centre pixel.
test::KernelPair Centred(const test::KernelPair& k) {
  const cv::Mat sum = k.left + k.right;
  const cv::Moments m = cv::moments(sum);
  const double dx = m.m10 / m.m00 - sum.cols / 2;
  const double dy = m.m01 / m.m00 - sum.rows / 2;
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, -dx, 0, 1, -dy);
  test::KernelPair out;
  const int p = 2;
  for (const auto& io : {std::make_pair(&k.left, &out.left),
                         std::make_pair(&k.right, &out.right)}) {
    cv::Mat padded;
    cv::copyMakeBorder(*io.first, padded, p, p, p, p, cv::BORDER_CONSTANT, 0);
    cv::warpAffine(padded,
                   *io.second,
                   shift,
                   padded.size(),
                   cv::INTER_LINEAR,
                   cv::BORDER_CONSTANT,
                   0);
  }
  return out;
}

// A sensor outside every family: an elliptical aperture with a rotated
// soft split on the left half of the frame, a cat-eye with a bright rim
// and a strong split on the right half. Kernels drawn directly at the
// capture's integer radius (no magnification by the code under test);
// nearer than the focus both views are rotated by 180 degrees.
test::KernelPair LeftHalf(int r) {
  return test::SoftSplitKernels(r, 0.75, 15, 2.0);
}
test::KernelPair RightHalf(int r) {
  return test::SoftSplitKernels(r, 1.0, 0, 6.0, 0.3, 1.5);
}

ShapeCapture Capture(int signed_radius, int seed, bool swap = false) {
  const int r = std::abs(signed_radius);
  test::KernelPair a = LeftHalf(r), b = RightHalf(r);
  if (signed_radius < 0) {
    for (cv::Mat* m : {&a.left, &a.right, &b.left, &b.right}) {
      cv::flip(*m, *m, -1);
    }
  }
  const cv::Mat scene = test::MakeTexture(cv::Size(320, 200), seed);
  ShapeCapture c;
  c.name = std::to_string(signed_radius) + " px";
  c.signed_radius_px = signed_radius;
  c.left = test::ConvolveWithOpenCV(scene, a.left);
  c.right = test::ConvolveWithOpenCV(scene, a.right);
  test::ConvolveWithOpenCV(scene, b.left)
      .colRange(160, 320)
      .copyTo(c.left.colRange(160, 320));
  test::ConvolveWithOpenCV(scene, b.right)
      .colRange(160, 320)
      .copyTo(c.right.colRange(160, 320));
  c.left = Noisy(c.left, seed + 1);
  c.right = Noisy(c.right, seed + 2);
  if (swap) std::swap(c.left, c.right);
  c.sharp = Noisy(0.3 * scene, seed + 3);  // a darker stopped-down exposure
  return c;
}

ShapeCalibrationOptions Options() {
  ShapeCalibrationOptions o;
  o.layout.rows = 1;
  o.layout.cols = 2;
  return o;
}

}  // namespace

// One plane farther and one nearer than the focus: each half of the frame
// gets its own kernels, whose disparity per radius is the truth's, and the
// far-side sample at the reference radius matches the truth's shape.
TEST(CalibrateShapes, OutOfFamilyKernelsPerCell) {
  const ShapeCalibration s =
      CalibrateShapes({Capture(6, 10), Capture(-4, 20)}, Options());
  std::printf("%s\n", s.reason.c_str());
  ASSERT_TRUE(s.determined) << s.reason;
  EXPECT_DOUBLE_EQ(s.reference_radius_px, 6);
  const double truth[2] = {Offset(LeftHalf(6), 6), Offset(RightHalf(6), 6)};
  for (int cell = 0; cell < 2; ++cell) {
    std::printf("cell %d: %.4f (truth %.4f); captures %.4f %.4f\n",
                cell,
                s.cell_centroid_offsets[cell],
                truth[cell],
                s.capture_cell_offsets[0][cell],
                s.capture_cell_offsets[1][cell]);
    EXPECT_NEAR(s.cell_centroid_offsets[cell] / truth[cell], 1.0, 0.05);
    EXPECT_NEAR(s.capture_cell_offsets[0][cell] / truth[cell], 1.0, 0.05);
    EXPECT_NEAR(s.capture_cell_offsets[1][cell] / truth[cell], 1.0, 0.08);
  }
  // The two halves differ as the truth does (the cat-eye splits harder).
  EXPECT_GT(s.cell_centroid_offsets[1], 1.3 * s.cell_centroid_offsets[0]);
  EXPECT_TRUE(std::isfinite(s.near_centroid_offset));
  EXPECT_TRUE(std::isfinite(s.far_centroid_offset));
  // Shape: the cell's kernels against the truth drawn at 6 px, both
  // normalised and centred on their views' sum (a shift both views share
  // is the two exposures' registration: unobservable, and it changes
  // nothing the estimator reads; the cat-eye's sum is off-centre).
  for (int cell = 0; cell < 2; ++cell) {
    const test::KernelPair t = Centred(cell == 0 ? LeftHalf(6) : RightHalf(6));
    const DPKernels& k = s.cell_kernels[cell];
    const int half = std::max(k.left.rows, t.left.rows) / 2;
    auto pad = [&](const cv::Mat& m) {
      cv::Mat out;
      const int p = half - m.rows / 2;
      cv::copyMakeBorder(
          m / cv::sum(m)[0], out, p, p, p, p, cv::BORDER_CONSTANT, 0);
      return out;
    };
    const double dl = cv::norm(pad(k.left), pad(t.left), cv::NORM_L1);
    const double dr = cv::norm(pad(k.right), pad(t.right), cv::NORM_L1);
    std::printf("cell %d: L1 shape error %.3f %.3f\n", cell, dl, dr);
    // The ellipse is smooth; the cat-eye's cut and bright rim are sharp
    // edges the smoothness penalty rounds off.
    const double bound = cell == 0 ? 0.15 : 0.35;
    EXPECT_LT(dl, bound);
    EXPECT_LT(dr, bound);
  }
}

// The stopped-down capture shot after a tripod nudge of (7, -5) px, beyond
// the kernel's window: the reference is registered first, and the kernels
// come out as without the nudge.
TEST(CalibrateShapes, NudgedReferenceIsRegistered) {
  ShapeCapture c = Capture(6, 60);
  const cv::Mat move = (cv::Mat_<double>(2, 3) << 1, 0, -7, 0, 1, 5);
  cv::Mat nudged;
  cv::warpAffine(c.sharp,
                 nudged,
                 move,
                 c.sharp.size(),
                 cv::INTER_NEAREST,
                 cv::BORDER_REFLECT);
  c.sharp = nudged;
  const ShapeCalibration s = CalibrateShapes({c}, Options());
  ASSERT_TRUE(s.determined) << s.reason;
  std::printf(
      "shift (%.2f, %.2f)\n", s.capture_shifts[0].x, s.capture_shifts[0].y);
  EXPECT_NEAR(s.capture_shifts[0].x, 7, 0.5);
  EXPECT_NEAR(s.capture_shifts[0].y, -5, 0.5);
  EXPECT_NEAR(s.cell_centroid_offsets[0] / Offset(LeftHalf(6), 6), 1.0, 0.05);
  EXPECT_NEAR(s.cell_centroid_offsets[1] / Offset(RightHalf(6), 6), 1.0, 0.05);
}

TEST(CalibrateShapes, RefusesWhatTheCapturesDoNotShow) {
  // Too little blur everywhere.
  const ShapeCalibration sharp = CalibrateShapes({Capture(1, 30)}, Options());
  EXPECT_FALSE(sharp.determined);
  EXPECT_NE(sharp.reason.find("no capture has a blur"), std::string::npos)
      << sharp.reason;
  // Views swapped: the kernels break the DP convention.
  const ShapeCalibration swapped =
      CalibrateShapes({Capture(6, 40, true)}, Options());
  EXPECT_FALSE(swapped.determined);
  EXPECT_NE(swapped.reason.find("swapped"), std::string::npos)
      << swapped.reason;
  // A "sharp reference" of another scene explains nothing.
  ShapeCapture other = Capture(6, 50);
  other.sharp = test::MakeTexture(other.sharp.size(), 999);
  const ShapeCalibration unrelated = CalibrateShapes({other}, Options());
  EXPECT_FALSE(unrelated.determined) << unrelated.reason;
  ShapeCalibrationOptions bad = Options();
  bad.min_radius_px = 0;
  EXPECT_FALSE(bad.Check());
  EXPECT_THROW(CalibrateShapes({other}, bad), std::invalid_argument);
}

}  // namespace dpsfm
