#include "dpsfm/core/optics/real_dft.h"
#include "dpsfm/core/util/check.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#ifdef DPSFM_WITH_FFTW
#include <fftw3.h>
#endif
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

namespace dpsfm {
namespace {

constexpr double kPi = 3.14159265358979323846;

// An image whose rows from `nonzero_rows` on are zero.
cv::Mat RandomImage(const cv::Size& size, int nonzero_rows, uint64_t seed) {
  cv::Mat image = cv::Mat::zeros(size, CV_32FC1);
  cv::RNG rng(seed);
  rng.fill(image.rowRange(0, nonzero_rows), cv::RNG::UNIFORM, -1.0, 1.0);
  return image;
}

// X(v, u) = sum_y,x x(y, x) exp(-2 pi i (v y / rows + u x / cols)), by the
// definition, in double.
std::complex<double> DftByDefinition(const cv::Mat& image, int v, int u) {
  std::complex<double> sum = 0;
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const double phase = -2 * kPi *
                           (static_cast<double>(v) * y / image.rows +
                            static_cast<double>(u) * x / image.cols);
      sum += static_cast<double>(image.at<float>(y, x)) *
             std::complex<double>(std::cos(phase), std::sin(phase));
    }
  }
  return sum;
}

// Circular convolution of x with y (same size), by the definition.
cv::Mat CircularConvolution(const cv::Mat& x, const cv::Mat& y) {
  cv::Mat out = cv::Mat::zeros(x.size(), CV_64FC1);
  for (int v = 0; v < x.rows; ++v) {
    for (int u = 0; u < x.cols; ++u) {
      double sum = 0;
      for (int i = 0; i < x.rows; ++i) {
        for (int j = 0; j < x.cols; ++j) {
          sum += x.at<float>(i, j) * y.at<float>((v - i + x.rows) % x.rows,
                                                 (u - j + x.cols) % x.cols);
        }
      }
      out.at<double>(v, u) = sum;
    }
  }
  return out;
}

// Every parity of rows and columns, a 1-D row, and partial rows.
const std::vector<cv::Size> kSizes = {
    {8, 6}, {9, 6}, {8, 7}, {9, 5}, {12, 1}, {1, 6}, {48, 48}, {25, 36}};

TEST(RealDft, TheHalfSpectrumByTheDefinition) {
  for (const cv::Size& size : kSizes) {
    const RealDft dft(size);
    ASSERT_EQ(dft.SpectrumSize(), cv::Size(size.width / 2 + 1, size.height));
    for (const int nonzero_rows : {size.height, (size.height + 1) / 2}) {
      const cv::Mat image = RandomImage(size, nonzero_rows, 7 + nonzero_rows);
      // Garbage where the rows are declared zero must not be read.
      cv::Mat declared = image.clone();
      declared.rowRange(nonzero_rows, size.height).setTo(1e6);
      // And a spectrum buffer holding garbage is written everywhere.
      cv::Mat spectrum(dft.SpectrumSize(), CV_32FC2, cv::Scalar(5, 5));
      dft.Forward(declared, nonzero_rows, &spectrum);
      ASSERT_EQ(spectrum.type(), CV_32FC2);
      ASSERT_EQ(spectrum.size(), dft.SpectrumSize());
      for (int v = 0; v < size.height; ++v) {
        for (int u = 0; u <= size.width / 2; ++u) {
          const std::complex<double> expected = DftByDefinition(image, v, u);
          const cv::Vec2f got = spectrum.at<cv::Vec2f>(v, u);
          EXPECT_NEAR(got[0], expected.real(), 1e-4 * size.area())
              << size << " (" << v << ", " << u << ")";
          EXPECT_NEAR(got[1], expected.imag(), 1e-4 * size.area())
              << size << " (" << v << ", " << u << ")";
        }
      }
    }
  }
}

TEST(RealDft, TheInverseGivesTheImageBackOnTheRowsAsked) {
  for (const cv::Size& size : kSizes) {
    const RealDft dft(size);
    const cv::Mat image = RandomImage(size, size.height, 3);
    const int h = size.height;
    // From the top, to the bottom, and inside: rows that start off FFTW's
    // alignment (an odd start where a row's half spectrum has an odd
    // length: 9, 25 and 48 wide) go through the work space's front.
    for (const cv::Range& rows : {cv::Range(0, h),
                                  cv::Range(0, (h + 1) / 2),
                                  cv::Range(h / 3, h),
                                  cv::Range(std::min(1, h - 1), h - h / 3),
                                  cv::Range(h / 2, h / 2)}) {
      cv::Mat spectrum;
      dft.Forward(image, size.height, &spectrum);
      cv::Mat back(size, CV_32FC1, cv::Scalar(-7));
      dft.Inverse(&spectrum, rows, &back);
      ASSERT_EQ(back.rows, rows.size()) << size;
      ASSERT_EQ(back.cols, size.width) << size;
      for (int y = 0; y < rows.size(); ++y) {
        for (int x = 0; x < size.width; ++x) {
          EXPECT_NEAR(
              back.at<float>(y, x), image.at<float>(rows.start + y, x), 1e-5)
              << size << " rows " << rows.start << "-" << rows.end << " (" << y
              << ", " << x << ")";
        }
      }
    }
  }
}

// Rows asked for alone are the same bits as in the whole inverse.
TEST(RealDft, RowsAskedForAloneAreTheWholeInversesBits) {
  for (const cv::Size& size : {cv::Size(48, 48),
                               cv::Size(64, 40),
                               cv::Size(72, 72),
                               cv::Size(50, 80)}) {
    const RealDft dft(size);
    const cv::Mat image = RandomImage(size, size.height, 9);
    cv::Mat spectrum, whole, part;
    dft.Forward(image, size.height, &spectrum);
    dft.Inverse(&spectrum, cv::Range(0, size.height), &whole);
    for (const int start : {1, 6, 7}) {
      dft.Forward(image, size.height, &spectrum);
      dft.Inverse(&spectrum, cv::Range(start, size.height - 5), &part);
      ASSERT_EQ(part.rows, size.height - 5 - start);
      EXPECT_EQ(0,
                std::memcmp(part.data,
                            whole.ptr<float>(start),
                            part.total() * part.elemSize()))
          << size << " from row " << start;
    }
  }
}

// The backend the build chose (CMake's DPSFM_WITH_FFTW) is the one that runs.
TEST(RealDft, TheBackendIsTheBuilds) {
#ifdef DPSFM_WITH_FFTW
  EXPECT_STREQ(RealDftBackend(), "FFTW");
#else
  EXPECT_STREQ(RealDftBackend(), "OpenCV");
#endif
}

TEST(RealDft, TheSameBitsEveryTime) {
  const cv::Size size(72, 48);
  const cv::Mat image = RandomImage(size, 40, 5);
  cv::Mat first, second;
  RealDft(size).Forward(image, 40, &first);
  RealDft(size).Forward(image, 40, &second);
  ASSERT_EQ(first.size(), second.size());
  EXPECT_EQ(0, std::memcmp(first.data, second.data,
                           first.total() * first.elemSize()));
}

#ifdef DPSFM_WITH_FFTW
// FFTW's in-place column pass over a half spectrum at `data` (rows x half,
// continuous), planned with FFTW_ESTIMATE as RealDft planned it before it
// ran some elsewhere.
fftwf_plan InPlaceColumnsPlan(int sign,
                              int rows,
                              int half,
                              fftwf_complex* data) {
  return fftwf_plan_many_dft(1,
                             &rows,
                             half,
                             data,
                             nullptr,
                             half,
                             1,
                             data,
                             nullptr,
                             half,
                             1,
                             sign,
                             FFTW_ESTIMATE);
}

// The in-place column passes over the half spectrum `s`.
void InPlaceColumns(int sign, cv::Mat* s) {
  fftwf_plan plan =
      InPlaceColumnsPlan(sign,
                         s->rows,
                         s->cols,
                         reinterpret_cast<fftwf_complex*>(s->ptr<float>()));
  fftwf_execute(plan);
  fftwf_destroy_plan(plan);
}

// RealDft runs the column passes between the spectrum and a work array
// where FFTW's plan for that computes the in-place plan's bits (decided on
// a probe, per size, on this machine), and in place elsewhere: either way
// the bits are the in-place passes'. The sizes are the searches' (both
// kinds occur among them: 40 and 48 px differ in kind where this was
// written).
TEST(RealDft, TheColumnPassesAreTheInPlacePassesBits) {
  for (const int n : {36, 40, 45, 48, 50, 54, 60, 64, 72, 80, 96, 100}) {
    const cv::Size size(n, n);
    const cv::Mat image = RandomImage(size, n, n);
    const RealDft dft(size);
    cv::Mat spectrum;
    dft.Forward(image, n, &spectrum);
    // The reference: rows, then columns in place.
    cv::Mat expected(n, n / 2 + 1, CV_32FC2);
    int cols = n;
    fftwf_plan rows = fftwf_plan_many_dft_r2c(
        1,
        &cols,
        n,
        const_cast<float*>(image.ptr<float>()),
        nullptr,
        1,
        n,
        reinterpret_cast<fftwf_complex*>(expected.ptr<float>()),
        nullptr,
        1,
        n / 2 + 1,
        FFTW_ESTIMATE);
    fftwf_execute(rows);
    fftwf_destroy_plan(rows);
    InPlaceColumns(FFTW_FORWARD, &expected);
    EXPECT_EQ(0,
              std::memcmp(spectrum.data,
                          expected.data,
                          expected.total() * expected.elemSize()))
        << "forward, " << size;
    // Inverse: the column pass is the only one that may run elsewhere; the
    // whole inverse against the in-place columns and RealDft's row pass
    // (the first row is aligned, so nothing is moved).
    cv::Mat columns = spectrum.clone();
    InPlaceColumns(FFTW_BACKWARD, &columns);
    cv::Mat through_dft, back;
    dft.Inverse(&spectrum, cv::Range(0, n), &through_dft);
    cv::Mat inverse_rows(n, n, CV_32FC1);
    fftwf_plan c2r = fftwf_plan_many_dft_c2r(
        1,
        &cols,
        n,
        reinterpret_cast<fftwf_complex*>(columns.ptr<float>()),
        nullptr,
        1,
        n / 2 + 1,
        inverse_rows.ptr<float>(),
        nullptr,
        1,
        n,
        FFTW_ESTIMATE);
    fftwf_execute(c2r);
    fftwf_destroy_plan(c2r);
    back = inverse_rows * (1.0 / size.area());
    EXPECT_EQ(0,
              std::memcmp(
                  through_dft.data, back.data, back.total() * back.elemSize()))
        << "inverse, " << size;
  }
}

// Where FFTW_ESTIMATE plans the in-place column pass through a buffer of
// all the columns (its plan printed as "(dft-buffered-<rows>-x<half>/<half>"),
// the buffered plan's first step planned alone computes its bits, so
// RealDft runs the pass without FFTW's copy back. The sizes are the
// searches'; which of them FFTW buffers depends on the machine's SIMD.
TEST(RealDft, WhereFftwBuffersTheColumnsTheyRunWithoutItsCopy) {
  int buffered = 0;
  for (const int n : {36, 40, 45, 48, 50, 54, 60, 64, 72, 80, 96, 100}) {
    const int half = n / 2 + 1;
    for (const int sign : {FFTW_FORWARD, FFTW_BACKWARD}) {
      fftwf_complex* data = fftwf_alloc_complex(n * half);
      fftwf_plan plan = InPlaceColumnsPlan(sign, n, half, data);
      char* printed = fftwf_sprint_plan(plan);
      const std::string prefix = "(dft-buffered-" + std::to_string(n) + "-x" +
                                 std::to_string(half) + "/" +
                                 std::to_string(half) + "-";
      const bool all_buffered = std::string(printed).rfind(prefix, 0) == 0;
      free(printed);
      fftwf_destroy_plan(plan);
      fftwf_free(data);
      if (!all_buffered) continue;
      ++buffered;
      EXPECT_NE(RealDft(cv::Size(n, n)).ColumnPassOf(sign == FFTW_FORWARD),
                RealDft::ColumnPass::kInPlace)
          << n << " px, " << (sign == FFTW_FORWARD ? "forward" : "inverse");
    }
  }
  if (buffered == 0) {
    GTEST_SKIP() << "FFTW buffers none of these column passes here";
  }
}

#endif  // DPSFM_WITH_FFTW

TEST(RealDft, RefusesWhatItCannotTransform) {
  EXPECT_THROW(RealDft(cv::Size(0, 4)), InternalError);
  const RealDft dft(cv::Size(8, 8));
  cv::Mat spectrum;
  const cv::Mat wider = cv::Mat::zeros(8, 12, CV_32FC1);
  EXPECT_THROW(dft.Forward(wider(cv::Rect(0, 0, 8, 8)), 8, &spectrum),
               InternalError)
      << "a view that is not continuous";
  EXPECT_THROW(dft.Forward(cv::Mat::zeros(8, 8, CV_64FC1), 8, &spectrum),
               InternalError);
  EXPECT_THROW(dft.Forward(cv::Mat::zeros(8, 8, CV_32FC1), 9, &spectrum),
               InternalError);
#ifdef DPSFM_WITH_FFTW
  // A continuous view that starts off FFTW's alignment.
  const cv::Mat rows = cv::Mat::zeros(9, 8, CV_32FC1);
  const cv::Mat shifted(8, 8, CV_32FC1, const_cast<float*>(rows.ptr<float>()) + 1);
  EXPECT_THROW(dft.Forward(shifted, 8, &spectrum), InternalError);
#endif
  cv::Mat image;
  cv::Mat wrong = cv::Mat::zeros(8, 4, CV_32FC2);
  EXPECT_THROW(dft.Inverse(&wrong, cv::Range(0, 8), &image),
               InternalError);
  cv::Mat right = cv::Mat::zeros(8, 5, CV_32FC2);
  EXPECT_THROW(dft.Inverse(&right, cv::Range(4, 9), &image),
               InternalError);
  EXPECT_THROW(dft.Inverse(&right, cv::Range(5, 4), &image),
               InternalError);
}

// The product difference, transformed back, is the difference of the
// circular convolutions by the definition.
TEST(SpectraProductDifference, TheDifferenceOfTwoCircularConvolutions) {
  for (const cv::Size& size : {cv::Size(8, 6), cv::Size(9, 5)}) {
    const RealDft dft(size);
    std::vector<cv::Mat> space(4), spectra(4);
    for (int k = 0; k < 4; ++k) {
      space[k] = RandomImage(size, size.height, 11 + k);
      dft.Forward(space[k], size.height, &spectra[k]);
    }
    cv::Mat product, back;
    SpectraProductDifference(
        spectra[0], spectra[1], spectra[2], spectra[3], &product);
    dft.Inverse(&product, cv::Range(0, size.height), &back);
    const cv::Mat expected = CircularConvolution(space[0], space[1]) -
                             CircularConvolution(space[2], space[3]);
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        EXPECT_NEAR(back.at<float>(y, x), expected.at<double>(y, x), 1e-4)
            << size << " (" << y << ", " << x << ")";
      }
    }
  }
}

TEST(SpectraProductDifference, RefusesSpectraOfDifferentSizes) {
  const cv::Mat a = cv::Mat::zeros(6, 5, CV_32FC2);
  const cv::Mat b = cv::Mat::zeros(6, 4, CV_32FC2);
  cv::Mat out;
  EXPECT_THROW(SpectraProductDifference(a, a, a, b, &out), std::exception);
  EXPECT_THROW(SpectraProductDifference(a, a, a, a, const_cast<cv::Mat*>(&a)),
               std::exception);
}

// The residual spectrum is each product rounded to float, then the
// differences, as the loop states it, to the bit: whichever clone of the
// loop the machine runs (real_dft.cc), no step is fused. Fused, the first
// products would round differently somewhere (the test can tell).
TEST(SpectraProductDifference, EachProductRoundedToTheBit) {
  std::vector<cv::Mat> s(4);
  for (int k = 0; k < 4; ++k) {
    s[k] = cv::Mat(9, 7, CV_32FC2);
    cv::randn(s[k], 0, k % 2 == 0 ? 300 : 0.7);
  }
  cv::Mat out;
  SpectraProductDifference(s[0], s[1], s[2], s[3], &out);
  ASSERT_EQ(out.size(), s[0].size());
  int fused_differs = 0;
  for (int k = 0; k < static_cast<int>(out.total()); ++k) {
    const cv::Vec2f a = s[0].at<cv::Vec2f>(k), b = s[1].at<cv::Vec2f>(k),
                    c = s[2].at<cv::Vec2f>(k), d = s[3].at<cv::Vec2f>(k);
    const float ab_re = a[0] * b[0], ab_re2 = a[1] * b[1];
    const float cd_re = c[0] * d[0], cd_re2 = c[1] * d[1];
    const float ab_im = a[0] * b[1], ab_im2 = a[1] * b[0];
    const float cd_im = c[0] * d[1], cd_im2 = c[1] * d[0];
    const float re = (ab_re - ab_re2) - (cd_re - cd_re2);
    const float im = (ab_im + ab_im2) - (cd_im + cd_im2);
    EXPECT_EQ(out.at<cv::Vec2f>(k)[0], re) << k;
    EXPECT_EQ(out.at<cv::Vec2f>(k)[1], im) << k;
    fused_differs += std::fma(a[0], b[0], -ab_re2) != ab_re - ab_re2;
  }
  EXPECT_GT(fused_differs, 0);
}

// The product of two spectra is cv::mulSpectrums's, to the bit (the
// intensity loss took it from there), on values whose products need the
// double sum to round as OpenCV rounds them; and it is refused where it
// cannot be formed.
TEST(SpectraProduct, CvMulSpectrumsToTheBit) {
  cv::Mat a(9, 7, CV_32FC2), b(9, 7, CV_32FC2);
  cv::randn(a, 0, 1000);
  cv::randn(b, 0, 1e-3);
  a.at<cv::Vec2f>(4, 3) = cv::Vec2f(1 + 1e-7f, 1);
  b.at<cv::Vec2f>(4, 3) = cv::Vec2f(1 - 1e-7f, 1);
  cv::Mat expected, product;
  cv::mulSpectrums(a, b, expected, 0);
  SpectraProduct(a, b, &product);
  ASSERT_EQ(product.type(), CV_32FC2);
  ASSERT_EQ(product.size(), a.size());
  EXPECT_EQ(std::memcmp(product.data, expected.data, a.total() * 8), 0);
  // A product in float alone is not it everywhere (the test can tell).
  int differ = 0;
  for (int k = 0; k < static_cast<int>(a.total()); ++k) {
    const cv::Vec2f x = a.at<cv::Vec2f>(k), y = b.at<cv::Vec2f>(k);
    differ += x[0] * y[0] - x[1] * y[1] != expected.at<cv::Vec2f>(k)[0];
  }
  EXPECT_GT(differ, 0);
  EXPECT_THROW(SpectraProduct(a, cv::Mat::zeros(9, 6, CV_32FC2), &product),
               std::exception);
  EXPECT_THROW(SpectraProduct(a, b, &a), std::exception);
}

}  // namespace
}  // namespace dpsfm
