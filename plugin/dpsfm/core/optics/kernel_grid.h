// The DP kernels of one DPPsfModel on a grid of signed radii, with their
// spectra for convolving a patch's interior: the shared precomputation of
// every stage that evaluates many patches at many radii (the blur search,
// the intensity search).
//
// Node n holds r_n = (n - HalfNodes()) * Step(). Between two nodes a kernel
// is interpolated linearly in r: K(r) = (1 - t) K(r_n) + t K(r_n+1). Its
// centroid (the quantity DP disparity measures) is then exactly linear in r,
// and any residual that is linear in the kernels is linear in t, so a
// squared loss is quadratic in t inside an interval: evaluating it at any r
// costs a few inner products of node quantities instead of a convolution.
// A 0.25 px step keeps the shape error of interpolation well below 0.01 px
// of r for the translating disk.
#pragma once

#include <algorithm>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/core/optics/dp_psf.h"
#include "dpsfm/core/optics/real_dft.h"

namespace dpsfm {

class DPKernelGrid {
 public:
  // Spectra for one interior size: node n's kernels reach Reach(n) pixels,
  // so its convolution on the interior reads the interior and that reach
  // around it; its spectra are taken at the DFT size of its class, the
  // fastest size that holds the interior and the largest reach of the
  // class's nodes (a node near focus transforms a third of the pixels a
  // node at the bound does).
  struct SpectrumClass {
    cv::Size dft_size;
    int reach = 0;
  };

  // Nodes cover [-bound, bound] with bound = max_radius_px rounded UP to a
  // multiple of step_px. interior_size: the part of a patch whose
  // convolution the spectra give; empty = no spectra. The nodes are
  // tabulated on num_threads threads (-1: all; psf.Kernels must be
  // thread-safe, as the models' are).
  DPKernelGrid(const DPPsfModel& psf,
               double step_px,
               double max_radius_px,
               const cv::Size& interior_size,
               int num_threads = 1);

  int NumNodes() const { return num_nodes_; }
  int HalfNodes() const { return half_nodes_; }
  double Step() const { return step_; }
  double Bound() const { return half_nodes_ * step_; }
  double Radius(int node) const { return (node - half_nodes_) * step_; }
  // psf.KernelRadius(Bound()): the border a patch needs for every node.
  int Border() const { return border_; }
  // Half the size of node n's kernels: how far its convolution reaches.
  int Reach(int node) const {
    return std::max(left_kernels_[node].rows, left_kernels_[node].cols) / 2;
  }

  // Interval of r (clamped to [-Bound(), Bound()]): r = (1 - *t) r_node +
  // *t r_(node+1) with node in [0, NumNodes() - 2] and t in [0, 1].
  void Locate(double signed_radius_px, int* node, double* t) const;

  const cv::Mat& LeftKernel(int node) const { return left_kernels_[node]; }
  const cv::Mat& RightKernel(int node) const { return right_kernels_[node]; }
  // Half spectra (RealDft) of the kernels wrapped around the origin
  // (WrapKernel), at the DFT size of the node's class: multiplied with
  // TransformInput of a patch for that class, and transformed back
  // (InteriorOfInverse), they give the true convolution on the interior.
  const cv::Mat& LeftSpectrum(int node) const { return left_spectra_[node]; }
  const cv::Mat& RightSpectrum(int node) const { return right_spectra_[node]; }
  int NumSpectrumClasses() const { return static_cast<int>(classes_.size()); }
  int SpectrumClassOf(int node) const { return class_of_[node]; }
  const SpectrumClass& SpectrumClassAt(int c) const { return classes_[c]; }
  // The transforms of class c's DFT size.
  const RealDft& Transform(int c) const { return transforms_[c]; }
  // The spectrum of class c's input: the interior of `patch` (at `border`
  // from its edges, border >= the class's reach) and the class's reach
  // around it, zero-padded to the class's DFT size.
  cv::Mat TransformInput(const cv::Mat& patch, int border, int c) const;
  // Where the interior lies in the inverse transform of a product with a
  // class c spectrum.
  cv::Rect InteriorOf(int c) const;
  // The interior of the inverse transform of *product (a product with a
  // class c spectrum; it is the transform's work space, and holds no
  // spectrum afterwards): only the interior's rows are computed, into
  // *image (reused when it has their size); the interior is a view into it.
  cv::Mat InteriorOfInverse(int c, cv::Mat* product, cv::Mat* image) const;

  // |h_l(n)|^2, |h_r(n)|^2 and, for n < NumNodes() - 1, <h_l(n), h_l(n+1)>,
  // <h_r(n), h_r(n+1)>: white noise of variance sigma^2 convolved with an
  // interpolated kernel has variance sigma^2 times the quadratic in t they
  // define (InterpolatedEnergy).
  double LeftEnergy(int node) const { return left_energy_[node]; }
  double RightEnergy(int node) const { return right_energy_[node]; }
  double LeftCross(int node) const { return left_cross_[node]; }
  // The kernels' sums: a constant c convolved with node n's left kernel is
  // c LeftSum(n) wherever the kernel's reach stays inside the patch.
  double LeftSum(int node) const { return left_sum_[node]; }
  double RightSum(int node) const { return right_sum_[node]; }
  double RightCross(int node) const { return right_cross_[node]; }

 private:
  void TabulateSpectra(int num_threads);
  // The node at minus node n's radius.
  int MirrorNode(int n) const { return num_nodes_ - 1 - n; }
  // The first node rendered and transformed; those below it are mirrored.
  int FirstRenderedNode() const { return mirrored_ ? half_nodes_ : 0; }

  double step_ = 0;
  int half_nodes_ = 0;
  int num_nodes_ = 0;
  int border_ = 0;
  // DPPsfModel::SwapsViewsWithSign: the nodes below r = 0 share the
  // kernels and spectra of those above.
  bool mirrored_ = false;
  cv::Size interior_size_;
  std::vector<SpectrumClass> classes_;
  std::vector<RealDft> transforms_;  // per class
  std::vector<int> class_of_;
  std::vector<cv::Mat> left_kernels_, right_kernels_;
  std::vector<cv::Mat> left_spectra_, right_spectra_;
  std::vector<double> left_energy_, right_energy_;
  std::vector<double> left_cross_, right_cross_;
  std::vector<double> left_sum_, right_sum_;
};

// The bound of a DPKernelGrid(psf, step_px, max_radius_px, ...): max_radius_px
// rounded up to a multiple of step_px.
double DPKernelGridBound(double max_radius_px, double step_px);

// The DFT size >= n of the kernel grids' classes: 2^a times 1, 3, 5, 9 or
// 25: the sizes cv::dft, RealDft's default backend, does fastest
// (cv::getOptimalDFTSize's 45, 75 or 81 cost it 1.2-2.2x the next such
// size, OpenCV 4.6 on 40-160 px); with FFTW's FFTW_ESTIMATE plans (the
// other backend) the sizes it gives for 30-130 px cost 3 % more than the
// fastest sizes measured (96 costs 1.7x 100) on average.
int FastDftSize(int n);

// (1 - t)^2 a + 2 t (1 - t) ab + t^2 b: the squared norm of
// (1 - t) x + t y given |x|^2 = a, <x, y> = ab, |y|^2 = b.
inline double InterpolatedEnergy(double a, double ab, double b, double t) {
  return (1 - t) * (1 - t) * a + 2 * t * (1 - t) * ab + t * t * b;
}

// Places a centred kernel into a zero matrix of `size` with its centre at
// (0, 0) and negative offsets wrapped around, so that the DFT product with a
// zero-padded image is the (circular) true convolution.
cv::Mat WrapKernel(const cv::Mat& kernel, const cv::Size& size);

// Embeds a centred kernel in a (2 half + 1)^2 zero frame, so that kernels of
// different sizes can be added and multiplied element-wise.
cv::Mat EmbedKernel(const cv::Mat& kernel, int half);

}  // namespace dpsfm
