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
  // A profile the same on both sides of focus gives node n < HalfNodes()
  // the kernels of its mirror node (Radius of one is exactly minus the
  // other's) with the views swapped: only r >= 0 is rendered.
  mirrored_ = psf.SwapsViewsWithSign();
  const int first = FirstRenderedNode();
  ParallelFor(num_nodes_ - first, num_threads, [&](int k) {
    const int n = first + k;
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
  for (int n = 0; n < first; ++n) {
    const int m = MirrorNode(n);
    left_kernels_[n] = right_kernels_[m];
    right_kernels_[n] = left_kernels_[m];
    left_energy_[n] = right_energy_[m];
    right_energy_[n] = left_energy_[m];
    left_sum_[n] = right_sum_[m];
    right_sum_[n] = left_sum_[m];
  }
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
  for (const SpectrumClass& c : classes_) transforms_.emplace_back(c.dft_size);
  left_spectra_.resize(num_nodes_);
  right_spectra_.resize(num_nodes_);
  // Mirrored nodes hold their mirror's kernels, so their spectra too (a
  // node's class follows from its kernels' size).
  const int first = FirstRenderedNode();
  ParallelFor(num_nodes_ - first, num_threads, [&](int k) {
    const int n = first + k;
    const RealDft& dft = transforms_[class_of_[n]];
    dft.Forward(WrapKernel(left_kernels_[n], dft.size()),
                dft.size().height,
                &left_spectra_[n]);
    dft.Forward(WrapKernel(right_kernels_[n], dft.size()),
                dft.size().height,
                &right_spectra_[n]);
  });
  for (int n = 0; n < first; ++n) {
    left_spectra_[n] = right_spectra_[MirrorNode(n)];
    right_spectra_[n] = left_spectra_[MirrorNode(n)];
  }
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
  transforms_[c].Forward(padded, input.height, &spectrum);
  return spectrum;
}

cv::Rect DPKernelGrid::InteriorOf(int c) const {
  const int reach = classes_[c].reach;
  return cv::Rect(cv::Point(reach, reach), interior_size_);
}

cv::Mat DPKernelGrid::InteriorOfInverse(int c,
                                        cv::Mat* product,
                                        cv::Mat* image) const {
  const cv::Rect interior = InteriorOf(c);
  transforms_[c].Inverse(
      product, cv::Range(interior.y, interior.y + interior.height), image);
  return image->colRange(interior.x, interior.x + interior.width);
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
