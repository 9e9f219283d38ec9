// RealDft's transforms on cv::dft, the default backend: OpenCV is already
// the core's image library, and its licence (Apache-2.0) keeps the default
// build permissive. cv::dft takes and gives full spectra, so the forward
// transform's half is copied out of a full one and the inverse's full
// spectrum is the half and its conjugate mirror; at the searches' sizes the
// copies cost a few per cent of the transforms. Both passes skip what
// nonzero_rows lets them: rows known to be zero going forward, rows not
// asked for coming back.
#include <opencv2/core.hpp>

#include "dpsfm/core/optics/real_dft.h"

namespace dpsfm {
namespace {

// The calling thread's full spectrum, reused between transforms.
cv::Mat& ThreadFullSpectrum() {
  thread_local cv::Mat full;
  return full;
}

// The full spectrum of a half spectrum (RealDft's layout) of a real image
// `cols` wide: F(v, u) = conj(F(-v mod rows, cols - u)) for u > cols / 2.
void MirrorHalfSpectrum(const cv::Mat& half, int cols, cv::Mat* full) {
  const int rows = half.rows;
  const int width = half.cols;
  full->create(rows, cols, CV_32FC2);
  half.copyTo(full->colRange(0, width));
  for (int v = 0; v < rows; ++v) {
    const cv::Vec2f* mirror = half.ptr<cv::Vec2f>((rows - v) % rows);
    cv::Vec2f* out = full->ptr<cv::Vec2f>(v);
    for (int u = width; u < cols; ++u) {
      const cv::Vec2f& z = mirror[cols - u];
      out[u] = cv::Vec2f(z[0], -z[1]);
    }
  }
}

}  // namespace

// Nothing to prepare per size: cv::dft plans each call.
struct RealDft::Plans {};

const RealDft::Plans* RealDft::PlansFor(const cv::Size&) {
  static const Plans none;
  return &none;
}

void RealDft::ForwardTransform(const cv::Mat& image,
                               int nonzero_rows,
                               cv::Mat* spectrum) const {
  cv::Mat& full = ThreadFullSpectrum();
  if (image.cols == 1) {
    // cv::dft refuses nonzero_rows on a single column: the rows declared
    // zero are zeroed in a copy instead (they must not be read).
    cv::Mat column = cv::Mat::zeros(image.size(), CV_32FC1);
    image.rowRange(0, nonzero_rows).copyTo(column.rowRange(0, nonzero_rows));
    cv::dft(column, full, cv::DFT_COMPLEX_OUTPUT);
  } else {
    cv::dft(image, full, cv::DFT_COMPLEX_OUTPUT, nonzero_rows);
  }
  full.colRange(0, spectrum->cols).copyTo(*spectrum);
}

void RealDft::InverseTransform(cv::Mat* spectrum,
                               const cv::Range& rows,
                               cv::Mat* image) const {
  cv::Mat& full = ThreadFullSpectrum();
  MirrorHalfSpectrum(*spectrum, size_.width, &full);
  thread_local cv::Mat back;
  // The first rows.end rows, the ones before rows.start computed for
  // nothing (cv::dft computes an inverse's rows from the top); all of a
  // single column's (cv::dft refuses nonzero_rows there).
  cv::dft(full,
          back,
          cv::DFT_INVERSE | cv::DFT_REAL_OUTPUT,
          size_.width == 1 ? 0 : rows.end);
  back.rowRange(rows).copyTo(*image);
}

const char* RealDftBackend() { return "OpenCV"; }

}  // namespace dpsfm
