// Real 2-D DFTs of one size, the one home of the searches' transforms.
//
// Two backends behind one interface, chosen when dp-sfm is built:
// - OpenCV's cv::dft (the default, real_dft_opencv.cc): permissively
//   licensed, as the rest of the default build is;
// - FFTW's single-precision plans (-DDPSFM_WITH_FFTW=ON,
//   real_dft_fftw.cc): 2-3x faster at the searches' sizes, GPL-2.0-or-later
//   (README, "Licence").
// Either computes a transform's bits from its size and input alone, so
// answers are the same run to run and at any thread count; the two
// backends' bits differ by rounding (docs/benchmark.md measures how far
// answers move between them).
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
  // Transforms of `size` (both sides >= 1). Whatever a backend prepares
  // per size is shared by every RealDft of that size and made at most once
  // per process.
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

#ifdef DPSFM_WITH_FFTW
  // How a direction's column pass runs on this machine, decided per size
  // when FFTW's plans are made (the fastest way found that computes the
  // in-place pass's bits): between the spectrum and a work array, into
  // contiguous columns whose rows are then gathered, or in place. For tests
  // and benchmarks.
  enum class ColumnPass { kApart, kThroughColumns, kInPlace };
  ColumnPass ColumnPassOf(bool forward) const;
#endif

 private:
  // What the backend keeps per size (its own definition).
  struct Plans;
  static const Plans* PlansFor(const cv::Size& size);
  // The backend's transforms, called with arguments Forward and Inverse
  // have checked and outputs they have allocated; the inverse unscaled.
  void ForwardTransform(const cv::Mat& image,
                        int nonzero_rows,
                        cv::Mat* spectrum) const;
  void InverseTransform(cv::Mat* spectrum,
                        const cv::Range& rows,
                        cv::Mat* image) const;

  cv::Size size_;
  const Plans* plans_ = nullptr;
};

// The backend this build transforms with: "OpenCV" or "FFTW".
const char* RealDftBackend();

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
