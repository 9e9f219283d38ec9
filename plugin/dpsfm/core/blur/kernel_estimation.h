// Measuring a DP kernel pair from a blurred capture and a sharp one of the
// same scene: the deconvolution behind a measured profile's shape.
//
// A textured plane shot twice from the same place, once with the aperture
// under test (each DP view is the plane convolved with that view's kernel)
// and once stopped down (almost no defocus), determines the kernels
// directly: B = k * S over the region, solved for k by least squares.
// Real kernels are small (2-5 px radius on a downsampled full-frame
// sensor) and the captures noisy, so the solve is regularised:
// - k >= 0 (a PSF carries light, it never removes it),
// - a squared-gradient penalty (kernels are smooth inside the aperture),
// - it runs on the images' derivatives, so an offset between the
//   exposures (flare, black level) cannot leak into the kernel.
// Each view's kernel is estimated against the same sharp image; the pair is
// then re-centred so that the sum of the views (the full-aperture defocus
// disk, symmetric about the point's image) sits at the centre pixel. That
// removes any small misregistration between the two exposures, which both
// views share; the DP disparity (the views' difference) is untouched.
#pragma once

#include <opencv2/core.hpp>

#include "dpsfm/core/optics/dp_psf.h"

namespace dpsfm {

struct KernelEstimationOptions {
  // Kernel support: the estimated kernel is (2 half_size + 1)^2 px.
  int half_size = 8;
  // Weight of the squared-gradient penalty, relative to the data term's
  // mean diagonal (scale free).
  double smoothness = 0.01;
  // Active-set steps of the non-negative solve (each adds one pixel to the
  // kernel's support).
  int max_iterations = 2000;
  bool Check(std::string* failure = nullptr) const;
};

struct EstimatedKernel {
  cv::Mat kernel;  // CV_32FC1, (2 half_size + 1)^2, centre = origin
  // ||B - k * S|| / ||B|| over the region (both zero-mean): how much of the
  // blurred image the kernel does not explain.
  double relative_residual = 0;
  int iterations = 0;
};

// Estimates the PSF k with blurred = k * sharp (true convolution, the
// kernel's centre pixel at the origin) over the region both images cover.
// `sharp`, `blurred`: CV_32FC1 or CV_64FC1, equal size, each side larger
// than 4 half_size + 8. The kernel's sum carries the ratio of the blurred
// image's contrast to the sharp one's: scale `sharp` to the blurred exposure
// first if that matters.
EstimatedKernel EstimateKernel(const cv::Mat& sharp,
                               const cv::Mat& blurred,
                               const KernelEstimationOptions& options);

struct EstimatedDPKernels {
  // Each view normalised to 0.5, re-centred (see the file comment).
  DPKernels kernels;
  // The shift removed (px): where the views' sum had its centroid.
  cv::Point2d recentred_by;
  // The views' light before normalisation, as fractions of their total.
  double left_share = 0.5;
  // The two kernels' total light, with the sharp image scaled to the
  // views' mean exposure: about 1 when the sharp image is the same view
  // (vignetting differences between the apertures move it a little), near
  // 0 when it is not (nothing correlates). Noise leaves it unbiased, unlike
  // the residual.
  double light_ratio = 1;
  double relative_residual = 0;  // the worse of the two views
};

// Both views against one sharp image (the stopped-down capture, both of
// its views summed). The sharp image is scaled to the blurred views' total
// exposure first, so left_share reflects the views' gains.
EstimatedDPKernels EstimateDPKernels(const cv::Mat& sharp,
                                     const cv::Mat& left,
                                     const cv::Mat& right,
                                     const KernelEstimationOptions& options);

// Shifts a kernel by (dx, dy) px with bilinear weights, keeping its size
// and its sum (light shifted past the border is dropped, then the rest is
// renormalised to the original sum).
cv::Mat ShiftKernel(const cv::Mat& kernel, double dx, double dy);

}  // namespace dpsfm
