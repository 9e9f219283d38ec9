// Dual-pixel point-spread functions.
//
// A DP sensor splits every pixel into a left and a right photodiode, so one
// exposure gives two views of the scene blurred by two different PSFs whose
// sum is the ordinary defocus disk. Everything in the core that needs those
// PSFs (the per-patch blur search, the intensity search, reports) gets them
// through DPPsfModel only, because real DP profiles depend on the lens, the
// aperture and the position in the frame and must stay replaceable
// (docs/psf-profiles.md).
//
// Conventions (the CLI contract's, docs/user-guide.md "Capturing"):
// - Signed blur radius r = b / (2 p) in pixels of the DP frame, r > 0 for a
//   point farther than the focal plane, r < 0 for a nearer one.
// - A point NEARER than the focal plane (r < 0) images in the LEFT view towards
//   +x (larger column) relative to the RIGHT view; a farther one towards -x.
//   Kernels are PSFs: a point at the origin images to the kernel, and they are
//   applied by true convolution (ConvolvePsf), so the left kernel's centroid
//   lies at larger x than the right one's when r < 0.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace dpsfm {

// Left and right DP point-spread functions for one signed blur radius.
struct DPKernels {
  // CV_32FC1, odd square size, centre pixel = origin. A point at the origin
  // images to this kernel; apply it by true convolution.
  cv::Mat left;
  // Same size. For the symmetric models right == flip_x(left);
  // left.sum() + right.sum() == 1.
  cv::Mat right;
};

// The replaceable DP PSF profile.
class DPPsfModel {
 public:
  virtual ~DPPsfModel() = default;

  // Identifies the profile INCLUDING its parameters: kernel caches (e.g. the
  // blur estimator's spectra) are keyed by it, so two models that return
  // different kernels must return different names.
  virtual std::string Name() const = 0;

  // signed_radius_px: r = b / (2 p) in pixels of the DP frame; r > 0 farther
  // than the focal plane, r < 0 nearer. Convention: for r < 0 the LEFT
  // kernel's centroid lies at larger x than the RIGHT one's; for r > 0 at
  // smaller x. |r| below the model's in-focus threshold (<= 0.5 px for the
  // disk) gives delta kernels of weight 0.5 each.
  virtual DPKernels Kernels(double signed_radius_px) const = 0;

  // Half-size of the kernels for |r| (kernel side = 2 * KernelRadius + 1), so
  // callers can size borders. Non-decreasing in |r|.
  virtual int KernelRadius(double signed_radius_px) const = 0;

  // True when Kernels(-r) is Kernels(r) with the views swapped, to the bit,
  // for every r (a profile the same nearer and farther than focus): a kernel
  // grid then renders and transforms each |r| once.
  virtual bool SwapsViewsWithSign() const { return false; }
};

// The ICCP 2020 / paper "translating disk", in its continuous form: a disk of
// radius R = |r| whose weight at (x, y) is the distance from the far end of
// its chord, x + sqrt(R^2 - y^2) (mirrored in x by the sign of r and between
// the views), integrated over the area of every pixel. The continuous
// profile's centroid sits at 3 pi / 32 R ~= 0.2945 R for every R. Sampled
// per pixel area, the kernel's centroid (taken at pixel centres) is off by
// +10 % at R = 1, +1.6 % at R = 2 and < 0.3 % from R = 4 on (disk edges cut
// pixels non-linearly; only a tent-shaped footprint would make it exact);
// the reference code's inclusive cumulative sum is far worse (0.24 R at
// R = 1, 0.26 R at R = 4), which reads small blurs too large.
//
// Continuity: the kernels are continuous in r everywhere. Pixel-area
// integration makes them exact deltas for |r| <= 0.5 (the disk then lies
// inside the centre pixel), so the in-focus threshold is 0.5 px and the step
// to a delta is continuous too; the unavoidable price is that blurs within
// half a pixel of focus are indistinguishable from focus. The kernel side
// grows by 2 when |r| + 0.5 crosses an integer, but the new outer pixels start
// at zero weight.
class TranslatingDiskPsf : public DPPsfModel {
 public:
  // `subsamples_per_pixel`: rows of the pixel-area integration per pixel row
  // (the integral along x is exact). 64 keeps the centroid within 1e-4 R of
  // 3 pi / 32 R at R >= 1 and costs well under a millisecond at R = 20.
  explicit TranslatingDiskPsf(int subsamples_per_pixel = 64);

  std::string Name() const override;
  DPKernels Kernels(double signed_radius_px) const override;
  int KernelRadius(double signed_radius_px) const override;
  // Kernels of |r|, assigned to the views by the sign of r.
  bool SwapsViewsWithSign() const override { return true; }

  // 3 pi / 32: centroid offset of each view's continuous profile from the
  // origin, in units of R (the pixel kernels approach it from R ~ 4 on).
  static double CentroidOffsetPerRadius();

 private:
  int subsamples_per_pixel_;
};

// A family of split profiles that differ from the translating disk in the
// ways real DP sensors do (docs/psf-profiles.md). The sum of the two views is
// the defocus disk of radius |r| (softened at the rim by rim_softness); how
// that disk's light divides between the views is:
// - split_exponent p: along each horizontal chord of the disk (half length
//   a), the view leaning towards +x receives (1 + g(x / a)) / 2 of the light
//   with g(t) = sign(t) |t|^p. p = 1 is a linear split (centroid offset
//   8 / (9 pi) R = 0.283 R; close to the translating disk's 3 pi / 32 R =
//   0.295 R, whose views sum to a disk weighted by chord length rather than a
//   uniform one); p -> 0 a sharp half-disk split (4 / (3 pi) R); p > 1 a
//   softer one.
// - crosstalk c: each view also receives the share c of the other's light
//   (centroid offset x (1 - 2 c)).
// - rim_softness e: the disk's rim is blurred by a Gaussian of sigma e |r|
//   (apodisation, residual aberrations).
// - rim_brightness b: the disk's light is weighted by 1 + b (rho / R)^2, a
//   bright rim (the Pixel 4's published kernels have one), which moves
//   each view's light outwards.
struct SplitProfileParams {
  double split_exponent = 1;
  double crosstalk = 0;
  double rim_softness = 0;
  double rim_brightness = 0;

  // Ranges in which the kernels stay meaningful: p in [0.05, 8], c in
  // [0, 0.45], e in [0, 0.5], b in [0, 4].
  bool Check(std::string* failure = nullptr) const;
  std::string ToString() const;

  // Each view's centroid offset from the origin in units of R, in closed
  // form (the rim's Gaussian keeps it): along a chord of half length a,
  // integral x g(x / a) dx = 2 a^2 / (p + 2) and, with the rim's x^2,
  // 2 a^4 / (p + 4); over the disk
  //   kappa = (1 - 2 c) [2 / (p + 2) (4/3 + 4 b / 15) + 32 b / (15 (p + 4))]
  //           / (pi (1 + b / 2)),
  // which is 8 / (3 pi (p + 2)) (1 - 2 c) without a bright rim.
  double CentroidOffset() const;
  // The one-parameter path through the family that self-calibration and
  // calibration search, by centroid offset kappa: kappa >= 8 / (9 pi)
  // (0.283) sharpens the split (p = 8 / (3 pi kappa) - 2, no crosstalk, up
  // to 0.414 at p = 0.05), beyond that the sharp split's rim brightens (up
  // to 0.472 at b = 4; a sharply split ring would be 2 / pi = 0.637),
  // smaller kappa keeps the linear split and adds crosstalk (down to 0.028
  // at c = 0.45), the way weak real splits behave.
  static SplitProfileParams ForCentroidOffset(double kappa);
  static double MinCentroidOffset();
  static double MaxCentroidOffset();
  // A range [min, max] of centroid offsets inside the family's (an options
  // check, core/util/check.h: false with the failing bound in *failure).
  static bool CheckCentroidOffsetRange(double min_centroid_offset,
                                       double max_centroid_offset,
                                       std::string* failure = nullptr);
};

class SplitProfilePsf : public DPPsfModel {
 public:
  explicit SplitProfilePsf(const SplitProfileParams& params,
                           int subsamples_per_pixel = 32);

  std::string Name() const override;
  DPKernels Kernels(double signed_radius_px) const override;
  int KernelRadius(double signed_radius_px) const override;
  // Kernels of |r|, assigned to the views by the sign of r.
  bool SwapsViewsWithSign() const override { return true; }

  const SplitProfileParams& Params() const { return params_; }

 private:
  SplitProfileParams params_;
  int subsamples_per_pixel_;
};

// A measured DP profile, the form published DP calibrations come in: a
// left/right kernel pair recorded at one reference blur radius on one side
// of the focus. Other radii scale the pair with |r| (the defocus cone is
// similar at every depth: the kernel of radius R is the reference one
// magnified R / R_ref, its light kept), and the other side of focus is the
// 180-degree rotation of each view's kernel (the cone inverts; each
// photodiode keeps seeing the same half of the exit pupil).
//
// Resampling treats every reference pixel as a uniform square of its
// weight and integrates it exactly over the output pixels (separable area
// overlaps), so the light is kept for every factor, the centroid scales
// with |r| (up to the output pixels' quantisation), and the kernels are
// continuous in r down to the delta at r = 0. cv::resize neither keeps a
// fixed centre pixel nor integrates when it magnifies.
class MeasuredKernelPsf : public DPPsfModel {
 public:
  // `left`, `right`: CV_32FC1 (or CV_64FC1), odd square, equal size, centre
  // pixel = origin, non-negative, each with positive sum. `far_side`: the
  // pair is for a point farther than the focus (r > 0), else nearer.
  // Each view is normalised to weight 0.5 (DP gain differences between the
  // views are the images' business: every stage equalises or normalises
  // them). Throws std::invalid_argument for malformed kernels, or when the
  // pair breaks the left/right convention (for a far point the left
  // kernel's centroid must lie at smaller x than the right one's).
  MeasuredKernelPsf(const cv::Mat& left,
                    const cv::Mat& right,
                    double reference_radius_px,
                    bool far_side);

  std::string Name() const override;
  DPKernels Kernels(double signed_radius_px) const override;
  int KernelRadius(double signed_radius_px) const override;

  double ReferenceRadius() const { return reference_radius_px_; }
  bool FarSide() const { return far_side_; }
  const cv::Mat& ReferenceLeft() const { return left_; }
  const cv::Mat& ReferenceRight() const { return right_; }

 private:
  cv::Mat left_, right_;  // CV_32FC1, 0.5 each
  double reference_radius_px_;
  bool far_side_;
  std::string name_;
};

// Magnifies a kernel (CV_32FC1, odd square, centre = origin) by `factor`
// about its centre pixel, keeping its sum: each input pixel becomes a
// uniform square of side `factor` whose weight is shared among the output
// pixels it overlaps. factor -> 0 gives a delta. The output has half-size
// MagnifiedHalfSize(half, factor) = ceil((half + 0.5) * factor - 0.5).
cv::Mat MagnifyKernel(const cv::Mat& kernel, double factor);
int MagnifiedHalfSize(int half, double factor);

// Where each of several DP PSF profiles applies: a rows x cols grid of
// equal cells over `region` (x0, y0, x1, y1 as fractions of the frame's
// width and height); outside it the nearest cell applies. Cells are
// numbered row-major. Column bands are the 1 x K grid over the frame.
struct DPPsfLayout {
  int rows = 1;
  int cols = 1;
  double x0 = 0, y0 = 0, x1 = 1, y1 = 1;

  static DPPsfLayout ColumnBands(int num_bands);
  int NumCells() const { return rows * cols; }
  // x_fraction, y_fraction: position in the frame, 0 (left / top edge) to 1.
  int CellAt(double x_fraction, double y_fraction) const;
  bool Check(std::string* failure = nullptr) const;
  std::string ToString() const;
};

// The DP PSF of a whole frame: one profile per cell of a layout (a single
// cell for a profile that does not change across the frame).
struct DPPsfField {
  DPPsfLayout layout;
  std::vector<std::shared_ptr<const DPPsfModel>> cells;  // layout.NumCells()

  static DPPsfField Uniform(std::shared_ptr<const DPPsfModel> psf);
  // The cell's profile at a position (fractions of the frame).
  const DPPsfModel& At(double x_fraction, double y_fraction) const;
  // Throws std::invalid_argument for a bad layout or a missing profile.
  void CheckValid() const;
  // The profile's name for one cell, else the layout and the cells' names
  // (the first and last of more than four).
  std::string Name() const;
};

// Centroid offset between the views per unit of |r|: (centroid_x(right) -
// centroid_x(left)) / (2 |r|) at a positive r (0.295 for the translating
// disk at large r). The quantity DP disparity measures; a profile with a
// different one scales every recovered radius by the ratio.
double CentroidOffsetPerRadius(const DPPsfModel& psf, double radius_px);
// The same of a kernel pair given at |r| = radius_px (far side).
double CentroidOffsetPerRadius(const DPKernels& kernels, double radius_px);

// True 2-D convolution (not correlation) of a CV_32FC1 or CV_32FC3 image with
// a PSF (CV_32FC1, odd width and height, centre = origin); output has the
// image's size and type, borders BORDER_REFLECT_101.
cv::Mat ConvolvePsf(const cv::Mat& image, const cv::Mat& psf);

// Centroid (x, y) of a kernel relative to its centre pixel, in pixels; x grows
// with the column. Throws for an empty or zero-sum kernel.
cv::Point2d KernelCentroid(const cv::Mat& kernel);

}  // namespace dpsfm
