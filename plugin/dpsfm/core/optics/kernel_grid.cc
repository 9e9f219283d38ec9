#include "dpsfm/core/optics/kernel_grid.h"

#include <algorithm>
#include <cmath>

#include "dpsfm/core/util/check.h"
#include "dpsfm/core/util/threads.h"

namespace dpsfm {
cv::Mat EmbedKernel(const cv::Mat& kernel, int half) {
  cv::Mat frame = cv::Mat::zeros(2 * half + 1, 2 * half + 1, CV_32FC1);
  const int oy = half - kernel.rows / 2;
  const int ox = half - kernel.cols / 2;
  kernel.copyTo(frame(cv::Rect(ox, oy, kernel.cols, kernel.rows)));
  return frame;
}

cv::Mat WrapKernel(const cv::Mat& kernel, const cv::Size& size) {
  cv::Mat wrapped = cv::Mat::zeros(size, CV_32FC1);
  const int cy = kernel.rows / 2;
  const int cx = kernel.cols / 2;
  for (int i = 0; i < kernel.rows; ++i) {
    const int y = ((i - cy) % size.height + size.height) % size.height;
    for (int j = 0; j < kernel.cols; ++j) {
      const int x = ((j - cx) % size.width + size.width) % size.width;
      wrapped.at<float>(y, x) += kernel.at<float>(i, j);
    }
  }
  return wrapped;
}

namespace {

// Entry i of column x (a CCS column is read down its rows).
struct Column {
  const cv::Mat& m;
  int x;
  float operator[](int y) const { return m.ptr<float>(y)[x]; }
};

// The complex product (re, im) of packed pairs, as cv::mulSpectrums
// computes it.
inline void ComplexProduct(
    double ar, double ai, double br, double bi, float* re, float* im) {
  *re = static_cast<float>(ar * br - ai * bi);
  *im = static_cast<float>(ar * bi + ai * br);
}

// One of the packed columns (0, and cols - 1 for an even width): real at
// row 0 (and the last row for an even height), complex pairs down the rows
// in between.
void ColumnProductDifference(const cv::Mat& a,
                             const cv::Mat& b,
                             const cv::Mat& c,
                             const cv::Mat& d,
                             int x,
                             cv::Mat* out) {
  const Column ca{a, x}, cb{b, x}, cc{c, x}, cd{d, x};
  const int rows = a.rows;
  out->ptr<float>(0)[x] = ca[0] * cb[0] - cc[0] * cd[0];
  for (int y = 1; y + 1 < rows; y += 2) {
    float ab_re, ab_im, cd_re, cd_im;
    ComplexProduct(ca[y], ca[y + 1], cb[y], cb[y + 1], &ab_re, &ab_im);
    ComplexProduct(cc[y], cc[y + 1], cd[y], cd[y + 1], &cd_re, &cd_im);
    out->ptr<float>(y)[x] = ab_re - cd_re;
    out->ptr<float>(y + 1)[x] = ab_im - cd_im;
  }
  if (rows % 2 == 0) {
    const int y = rows - 1;
    out->ptr<float>(y)[x] = ca[y] * cb[y] - cc[y] * cd[y];
  }
}

}  // namespace

void SpectraProductDifference(const cv::Mat& a,
                              const cv::Mat& b,
                              const cv::Mat& c,
                              const cv::Mat& d,
                              cv::Mat* out) {
  DPSFM_CHECK(a.type() == CV_32FC1 && b.type() == CV_32FC1 &&
              c.type() == CV_32FC1 && d.type() == CV_32FC1)
      << "SpectraProductDifference takes CCS-packed CV_32FC1 spectra";
  DPSFM_CHECK(a.size() == b.size() && a.size() == c.size() &&
              a.size() == d.size())
      << "SpectraProductDifference takes spectra of one size";
  DPSFM_CHECK(a.rows > 1 && a.cols > 1)
      << "SpectraProductDifference takes 2-D spectra";
  DPSFM_CHECK(out->data != a.data && out->data != b.data &&
              out->data != c.data && out->data != d.data)
      << "SpectraProductDifference writes to a matrix of its own";
  out->create(a.size(), CV_32FC1);
  const int cols = a.cols;
  ColumnProductDifference(a, b, c, d, 0, out);
  if (cols % 2 == 0) ColumnProductDifference(a, b, c, d, cols - 1, out);
  // The rows' complex pairs: columns 1 .. last before a packed column.
  const int end = cols % 2 == 0 ? cols - 1 : cols;
  for (int y = 0; y < a.rows; ++y) {
    const float* pa = a.ptr<float>(y);
    const float* pb = b.ptr<float>(y);
    const float* pc = c.ptr<float>(y);
    const float* pd = d.ptr<float>(y);
    float* po = out->ptr<float>(y);
    for (int j = 1; j < end; j += 2) {
      float ab_re, ab_im, cd_re, cd_im;
      ComplexProduct(pa[j], pa[j + 1], pb[j], pb[j + 1], &ab_re, &ab_im);
      ComplexProduct(pc[j], pc[j + 1], pd[j], pd[j + 1], &cd_re, &cd_im);
      po[j] = ab_re - cd_re;
      po[j + 1] = ab_im - cd_im;
    }
  }
}

int FastDftSize(int n) {
  DPSFM_CHECK_GT(n, 0);
  int best = 0;
  for (const int odd : {1, 3, 5, 9, 25}) {
    int size = odd;
    while (size < n) size *= 2;
    if (best == 0 || size < best) best = size;
  }
  return best;
}

DPKernelGrid::DPKernelGrid(const DPPsfModel& psf,
                           double step_px,
                           double max_radius_px,
                           const cv::Size& interior_size,
                           int num_threads)
    : step_(step_px), interior_size_(interior_size) {
  DPSFM_CHECK(step_px > 0 && std::isfinite(step_px))
      << "kernel grid step must be positive, got " << step_px;
  DPSFM_CHECK(max_radius_px >= 0 && std::isfinite(max_radius_px))
      << "kernel grid bound must be >= 0, got " << max_radius_px;
  half_nodes_ =
      std::max(1, static_cast<int>(std::ceil(max_radius_px / step_px - 1e-9)));
  num_nodes_ = 2 * half_nodes_ + 1;
  border_ = psf.KernelRadius(Bound());
  left_kernels_.resize(num_nodes_);
  right_kernels_.resize(num_nodes_);
  left_energy_.resize(num_nodes_);
  right_energy_.resize(num_nodes_);
  left_sum_.resize(num_nodes_);
  right_sum_.resize(num_nodes_);
  left_cross_.assign(num_nodes_, 0.0);
  right_cross_.assign(num_nodes_, 0.0);
  ParallelFor(num_nodes_, num_threads, [&](int n) {
    const DPKernels kernels = psf.Kernels(Radius(n));
    DPSFM_CHECK(kernels.left.type() == CV_32FC1 &&
                kernels.right.type() == CV_32FC1 &&
                kernels.left.size() == kernels.right.size() &&
                kernels.left.rows % 2 == 1 && kernels.left.cols % 2 == 1)
        << psf.Name() << ": kernels must be CV_32FC1, odd, of equal size";
    DPSFM_CHECK(kernels.left.rows <= 2 * border_ + 1 &&
                kernels.left.cols <= 2 * border_ + 1)
        << psf.Name() << ": kernel at r = " << Radius(n)
        << " exceeds KernelRadius(" << Bound() << ")";
    left_kernels_[n] = kernels.left;
    right_kernels_[n] = kernels.right;
    const cv::Mat left = EmbedKernel(kernels.left, border_);
    const cv::Mat right = EmbedKernel(kernels.right, border_);
    left_energy_[n] = left.dot(left);
    right_energy_[n] = right.dot(right);
    left_sum_[n] = cv::sum(kernels.left)[0];
    right_sum_[n] = cv::sum(kernels.right)[0];
  });
  ParallelFor(num_nodes_ - 1, num_threads, [&](int n) {
    left_cross_[n] = EmbedKernel(left_kernels_[n], border_)
                         .dot(EmbedKernel(left_kernels_[n + 1], border_));
    right_cross_[n] = EmbedKernel(right_kernels_[n], border_)
                          .dot(EmbedKernel(right_kernels_[n + 1], border_));
  });
  if (interior_size.area() > 0) TabulateSpectra(num_threads);
}

// Each node's class by the DFT size its interior and reach need (the reach
// grows with |r|, so a class is a band of |r|), then the spectra at it.
void DPKernelGrid::TabulateSpectra(int num_threads) {
  class_of_.resize(num_nodes_);
  for (int n = 0; n < num_nodes_; ++n) {
    const int reach = Reach(n);
    const cv::Size dft(FastDftSize(interior_size_.width + 2 * reach),
                       FastDftSize(interior_size_.height + 2 * reach));
    auto it = std::find_if(
        classes_.begin(), classes_.end(), [&](const SpectrumClass& c) {
          return c.dft_size == dft;
        });
    if (it == classes_.end()) {
      classes_.push_back(SpectrumClass{dft, reach});
      it = classes_.end() - 1;
    }
    it->reach = std::max(it->reach, reach);
    class_of_[n] = static_cast<int>(it - classes_.begin());
  }
  left_spectra_.resize(num_nodes_);
  right_spectra_.resize(num_nodes_);
  ParallelFor(num_nodes_, num_threads, [&](int n) {
    const cv::Size& dft = classes_[class_of_[n]].dft_size;
    cv::dft(WrapKernel(left_kernels_[n], dft), left_spectra_[n]);
    cv::dft(WrapKernel(right_kernels_[n], dft), right_spectra_[n]);
  });
}

cv::Mat DPKernelGrid::TransformInput(const cv::Mat& patch,
                                     int border,
                                     int c) const {
  const SpectrumClass& k = classes_[c];
  DPSFM_CHECK(patch.type() == CV_32FC1 && border >= k.reach &&
              patch.cols == interior_size_.width + 2 * border &&
              patch.rows == interior_size_.height + 2 * border)
      << "a " << patch.cols << "x" << patch.rows << " patch with border "
      << border << " for an interior of " << interior_size_.width << "x"
      << interior_size_.height << " and kernels reaching " << k.reach << " px";
  const cv::Rect input(border - k.reach,
                       border - k.reach,
                       interior_size_.width + 2 * k.reach,
                       interior_size_.height + 2 * k.reach);
  cv::Mat padded = cv::Mat::zeros(k.dft_size, CV_32FC1);
  patch(input).copyTo(padded(cv::Rect(cv::Point(0, 0), input.size())));
  cv::Mat spectrum;
  cv::dft(padded, spectrum, 0, input.height);
  return spectrum;
}

cv::Rect DPKernelGrid::InteriorOf(int c) const {
  const int reach = classes_[c].reach;
  return cv::Rect(cv::Point(reach, reach), interior_size_);
}

double DPKernelGridBound(double max_radius_px, double step_px) {
  return std::max(1,
                  static_cast<int>(std::ceil(max_radius_px / step_px - 1e-9))) *
         step_px;
}

void DPKernelGrid::Locate(double signed_radius_px, int* node, double* t) const {
  const double bound = Bound();
  double r = std::isfinite(signed_radius_px)
                 ? signed_radius_px
                 : (signed_radius_px > 0 ? bound : -bound);
  r = std::max(-bound, std::min(bound, r));
  const double position = r / step_ + half_nodes_;
  int n = static_cast<int>(std::floor(position));
  n = std::max(0, std::min(num_nodes_ - 2, n));
  *node = n;
  *t = std::max(0.0, std::min(1.0, position - n));
}

}  // namespace dpsfm
