// The DP kernels of one DPPsfModel on a grid of signed radii, with their
// spectra at one DFT size: the shared precomputation of every stage that
// evaluates many patches at many radii (the blur search, the intensity
// search).
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

#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/core/optics/dp_psf.h"

namespace dpsfm {

class DPKernelGrid {
 public:
  // Nodes cover [-bound, bound] with bound = max_radius_px rounded UP to a
  // multiple of step_px. dft_size: the (zero-padded) size at which spectra
  // are taken; empty = no spectra.
  DPKernelGrid(const DPPsfModel& psf,
               double step_px,
               double max_radius_px,
               const cv::Size& dft_size);

  // The grid's bound for a step and a search bound, without building it.
  static double BoundFor(double step_px, double max_radius_px);

  int NumNodes() const { return num_nodes_; }
  int HalfNodes() const { return half_nodes_; }
  double Step() const { return step_; }
  double Bound() const { return half_nodes_ * step_; }
  double Radius(int node) const { return (node - half_nodes_) * step_; }
  // psf.KernelRadius(Bound()): the border a patch needs for every node.
  int Border() const { return border_; }
  const cv::Size& DftSize() const { return dft_size_; }

  // Interval of r (clamped to [-Bound(), Bound()]): r = (1 - *t) r_node +
  // *t r_(node+1) with node in [0, NumNodes() - 2] and t in [0, 1].
  void Locate(double signed_radius_px, int* node, double* t) const;

  const cv::Mat& LeftKernel(int node) const { return left_kernels_[node]; }
  const cv::Mat& RightKernel(int node) const { return right_kernels_[node]; }
  // CCS-packed real DFTs (cv::dft default) of the kernels wrapped around the
  // origin (WrapKernel): multiplying with the DFT of a patch zero-padded to
  // DftSize() convolves it, exactly wherever the kernel's reach stays inside
  // the patch.
  const cv::Mat& LeftSpectrum(int node) const { return left_spectra_[node]; }
  const cv::Mat& RightSpectrum(int node) const { return right_spectra_[node]; }

  // |h_l(n)|^2, |h_r(n)|^2 and, for n < NumNodes() - 1, <h_l(n), h_l(n+1)>,
  // <h_r(n), h_r(n+1)>: white noise of variance sigma^2 convolved with an
  // interpolated kernel has variance sigma^2 times the quadratic in t they
  // define (InterpolatedEnergy).
  double LeftEnergy(int node) const { return left_energy_[node]; }
  double RightEnergy(int node) const { return right_energy_[node]; }
  double LeftCross(int node) const { return left_cross_[node]; }
  double RightCross(int node) const { return right_cross_[node]; }

 private:
  double step_ = 0;
  int half_nodes_ = 0;
  int num_nodes_ = 0;
  int border_ = 0;
  cv::Size dft_size_;
  std::vector<cv::Mat> left_kernels_, right_kernels_;
  std::vector<cv::Mat> left_spectra_, right_spectra_;
  std::vector<double> left_energy_, right_energy_;
  std::vector<double> left_cross_, right_cross_;
};

// The bound of a DPKernelGrid(psf, step_px, max_radius_px, ...): max_radius_px
// rounded up to a multiple of step_px.
double DPKernelGridBound(double max_radius_px, double step_px);

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
