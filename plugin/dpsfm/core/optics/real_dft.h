// Real 2-D DFTs of one size, the one home of the searches' transforms.
//
// FFTW's single-precision plans rather than cv::dft: at the searches' sizes
// (48-144 px) cv::dft (OpenCV 4.6, as Debian 12 builds it, without IPP)
// takes 2-3x FFTW's time (docs/benchmark.md), and the blur and intensity
// searches spend about half their time in transforms. The plans are made
// with FFTW_ESTIMATE: a transform's arithmetic then depends on its size and
// nothing else (FFTW_MEASURE's choice depends on timings), so answers are
// the same run to run and at any thread count.
//
// A 2-D transform is done in two passes, rows then columns (forward) and
// columns then rows (inverse), so that rows known to be zero are not
// transformed and rows not needed are not computed back (what cv::dft's
// nonzero_rows does). The column pass runs between the spectrum and a
// per-thread work array, or into contiguous columns there, where FFTW
// computes the same bits that way as in place (checked per size when the
// plans are made), because it then needs no buffers.
//
// Spectra are half spectra: CV_32FC2, rows x (cols / 2 + 1), the columns
// u = 0 .. cols / 2 of the full spectrum (the others are their conjugate
// mirror), as cv::dft's DFT_COMPLEX_OUTPUT gives them; products of half
// spectra are element-wise complex products.
#pragma once

#include <opencv2/core.hpp>

namespace dpsfm {

class RealDft {
 public:
  // Transforms of `size` (both sides >= 1). Plans are shared by every
  // RealDft of the same size and made at most once per process.
  explicit RealDft(const cv::Size& size);

  const cv::Size& size() const { return size_; }
  cv::Size SpectrumSize() const {
    return cv::Size(size_.width / 2 + 1, size_.height);
  }

  // The half spectrum of `image` (CV_32FC1 of size(), continuous), whose
  // rows from `nonzero_rows` on are zero (and not read), into *spectrum
  // (reallocated unless it is a continuous CV_32FC2 of SpectrumSize()).
  void Forward(const cv::Mat& image, int nonzero_rows, cv::Mat* spectrum) const;

  // Rows `rows` of the real inverse of the half spectrum *spectrum divided
  // by the area (cv::DFT_SCALE), into *image: CV_32FC1, rows.size() x
  // size().width, its row 0 the inverse's row rows.start (reallocated unless
  // it is a continuous matrix of that size). Only those rows are computed
  // in the second pass: the searches keep a patch's interior, below a
  // border of rows that would be computed for nothing. *spectrum is the
  // work space: it holds no spectrum afterwards.
  void Inverse(cv::Mat* spectrum, const cv::Range& rows, cv::Mat* image) const;

  // A half spectrum of SpectrumSize(), continuous, as the transforms need.
  cv::Mat NewSpectrum() const;

  // How a direction's column pass runs on this machine, decided per size
  // when the plans are made (the fastest way found that computes the
  // in-place pass's bits): between the spectrum and a work array, into
  // contiguous columns whose rows are then gathered, or in place. For tests
  // and benchmarks.
  enum class ColumnPass { kApart, kThroughColumns, kInPlace };
  ColumnPass ColumnPassOf(bool forward) const;

 private:
  struct Plans;
  cv::Size size_;
  const Plans* plans_ = nullptr;
};

// a * b, element-wise complex, for half spectra of one size (RealDft), into
// *out: cv::mulSpectrums's arithmetic to the bit (each part summed in double
// from the exact products, rounded once), in a loop that vectorises.
void SpectraProduct(const cv::Mat& a, const cv::Mat& b, cv::Mat* out);

// a * b - c * d, element-wise complex, for half spectra of one size (RealDft),
// into *out: the residual spectrum of the blur refinement in one pass.
void SpectraProductDifference(const cv::Mat& a,
                              const cv::Mat& b,
                              const cv::Mat& c,
                              const cv::Mat& d,
                              cv::Mat* out);

}  // namespace dpsfm
