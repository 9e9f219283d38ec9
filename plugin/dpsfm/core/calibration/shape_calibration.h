// A DP profile's shape from calibration captures: each capture of the
// textured plane with the aperture under test, paired with a stopped-down
// capture of the same plane from the same place (the sharp reference),
// gives every cell of the frame its left/right kernel pair by
// deconvolution (EstimateDPKernels). The blur radius of each capture comes
// from the thin lens at the calibrated focus (CalibrateFromTargets), so
// each measured pair is one sample of the profile at a known radius: it is
// magnified to a common reference radius (MagnifyKernel, the defocus cone
// being similar at every depth) and rotated by 180 degrees when it was
// nearer than the focus, and the samples of a cell are averaged. The
// reference is first moved onto the capture by whole pixels (the peak of
// their cross-correlation, within 24 px), so a tripod nudged between the
// exposures does not push the kernel out of its window. What the
// shape says of the strength (its centroid offset per radius) is reported
// per capture, nearer and farther than the focus separately.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "dpsfm/core/blur/kernel_estimation.h"
#include "dpsfm/core/optics/dp_psf.h"

namespace dpsfm {

struct ShapeCapture {
  std::string name;
  // The DP views at the aperture under test (grey, CV_32FC1, the working
  // resolution) and the sharp reference of the same target (both of its
  // views summed), all of one size.
  cv::Mat left, right, sharp;
  // The capture's blur radius (px, signed: > 0 farther than the focus).
  double signed_radius_px = 0;
};

struct ShapeCalibrationOptions {
  // Cells measured on their own (the frame's region as in DPPsfLayout).
  DPPsfLayout layout;
  // The radius the averaged kernels are given at; 0 = the largest |r| of
  // the captures used (magnifying a small measured kernel also magnifies
  // its pixel-level blur, so the largest sample needs no magnification).
  double reference_radius_px = 0;
  // A capture whose |r| is smaller than this shows no shape to measure.
  double min_radius_px = 1.5;
  // Kernel half-size: ceil(support_factor |r|) + support_margin_px (room
  // for soft rims and a misregistration of the two exposures).
  double support_factor = 1.3;
  int support_margin_px = 3;
  // Regularisation of the deconvolution (KernelEstimationOptions).
  double smoothness = 0.01;
  // A cell whose kernels carry less or more than this share of the light
  // the exposures predict (EstimatedDPKernels::light_ratio) is not a
  // measurement: the sharp capture is not of the same view, or moved. (The
  // residual is no test: on real captures noise dominates it.)
  double min_light_ratio = 0.6;
  double max_light_ratio = 1.5;
  bool Check(std::string* failure = nullptr) const;
};

struct ShapeCalibration {
  bool determined = false;
  std::string reason;  // why not, or a summary
  DPPsfLayout layout;
  double reference_radius_px = 0;
  // Per cell (row-major): the averaged pair at the reference radius, far
  // side (left view towards -x), and its centroid offset per radius.
  std::vector<DPKernels> cell_kernels;
  std::vector<double> cell_centroid_offsets;
  // Per capture: used or why not, and per cell the measured centroid
  // offset per radius, the deconvolution's relative residual and the
  // kernels' light ratio.
  std::vector<std::string> capture_names;
  std::vector<bool> capture_used;
  std::vector<std::string> capture_notes;
  std::vector<std::vector<double>> capture_cell_offsets;
  std::vector<std::vector<double>> capture_cell_residuals;
  std::vector<std::vector<double>> capture_cell_light;
  // Where the blurred views lie against the sharp reference (whole px,
  // cross-correlation; undone before measuring).
  std::vector<cv::Point2d> capture_shifts;
  // Patch-weighted mean centroid offsets of the captures nearer and
  // farther than the focus (NaN where there are none), and the largest
  // relative deviation of one capture's cell offset from the cell's mean.
  double near_centroid_offset = std::numeric_limits<double>::quiet_NaN();
  double far_centroid_offset = std::numeric_limits<double>::quiet_NaN();
  double spread = 0;
};

ShapeCalibration CalibrateShapes(const std::vector<ShapeCapture>& captures,
                                 const ShapeCalibrationOptions& options);

// The measured shape's overall strength: the geometric mean of the cells'
// centroid offsets weighted as the strength fit weights them (by their
// patches, at least 1 each; TargetCalibration::cell_patches).
double MeasuredStrength(const ShapeCalibration& shape,
                        const std::vector<int>& cell_weights);

}  // namespace dpsfm
