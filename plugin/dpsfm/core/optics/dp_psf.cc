#include "dpsfm/core/optics/dp_psf.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <sstream>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "dpsfm/core/util/check.h"

namespace dpsfm {
namespace {

// The disk of radius R cut into the pieces each kernel pixel integrates:
// for pixel rows i in [0, half] (kernel coordinates, centre = 0; row i
// covers y in [i - 0.5, i + 0.5]), `subsamples` midpoint sub-rows y each,
// and every pixel column j >= first_column that the chord of half length
// a = sqrt(R^2 - y^2) at y reaches, calls piece(i, j, lo, hi, a) with
// [lo, hi] = [j - 0.5, j + 0.5] cut to the chord. A profile integrates its
// weight along x over [lo, hi] exactly and multiplies by the sub-row height
// 1 / subsamples. Rows below the centre are the profiles' mirror images
// (MirrorRowsBelowCentre); first_column = 0 leaves out columns left of the
// centre too, for a profile that mirrors them (MirrorColumnsLeftOfCentre).
template <typename Piece>
void ForEachChordPiece(
    double radius, int half, int subsamples, int first_column, Piece piece) {
  const double r2 = radius * radius;
  const double dy = 1.0 / subsamples;
  for (int i = 0; i <= half; ++i) {
    for (int s = 0; s < subsamples; ++s) {
      const double y = i - 0.5 + (s + 0.5) * dy;
      const double y2 = y * y;
      if (y2 >= r2) continue;
      const double a = std::sqrt(r2 - y2);  // half chord
      const int j_begin =
          std::max(first_column, static_cast<int>(std::floor(-a + 0.5)));
      const int j_end = std::min(half, static_cast<int>(std::ceil(a - 0.5)));
      for (int j = j_begin; j <= j_end; ++j) {
        const double lo = std::max(j - 0.5, -a);
        const double hi = std::min(j + 0.5, a);
        if (hi <= lo) continue;
        piece(i, j, lo, hi, a);
      }
    }
  }
}

// The two views' kernels from the one whose mass leans towards +x and the
// one leaning towards -x. Near (r < 0): the view leaning +x is the left one
// (cli contract).
DPKernels AssignBySign(double signed_radius_px,
                       const cv::Mat& towards_plus_x,
                       const cv::Mat& towards_minus_x) {
  DPKernels kernels;
  if (signed_radius_px < 0) {
    kernels.left = towards_plus_x;
    kernels.right = towards_minus_x;
  } else {
    kernels.left = towards_minus_x;
    kernels.right = towards_plus_x;
  }
  return kernels;
}

// Profiles symmetric in y integrate the kernel rows i >= 0
// (ForEachChordPiece) and copy them onto the rows below the centre, so the
// kernel is exactly symmetric: `weights` is side x side, row-major, side =
// 2 half + 1.
void MirrorRowsBelowCentre(int half, std::vector<double>* weights) {
  const int side = 2 * half + 1;
  for (int i = 1; i <= half; ++i) {
    std::copy(weights->begin() + (half + i) * side,
              weights->begin() + (half + i + 1) * side,
              weights->begin() + (half - i) * side);
  }
}

// A pair of kernels each the other's mirror image in x (`plus` leans
// towards +x, `minus` towards -x) integrated on the columns j >= 0 of rows
// i >= 0 (ForEachChordPiece from first_column 0): the columns left of the
// centre are copied from the other kernel's right of it. A piece's
// integral and its mirror piece's are the same numbers with the split part
// negated, added in the same order, so the copies are what integrating
// them would give, to the bit, at half the work.
void MirrorColumnsLeftOfCentre(int half,
                               std::vector<double>* plus,
                               std::vector<double>* minus) {
  const int side = 2 * half + 1;
  for (int i = half; i < side; ++i) {
    double* p = plus->data() + i * side + half;
    double* m = minus->data() + i * side + half;
    for (int j = 1; j <= half; ++j) {
      p[-j] = m[j];
      m[-j] = p[j];
    }
  }
}

// Pixel-area integral of the translating-disk profile whose mass leans
// towards +x: weight(x, y) = x + sqrt(R^2 - y^2) inside the disk of radius R.
// Row i of the kernel covers y in [i - 0.5, i + 0.5], column j covers x in
// [j - 0.5, j + 0.5] (kernel coordinates, centre = 0). Along x the integral is
// exact; along y a midpoint rule with `subsamples` rows per pixel. Every
// sample depends continuously on R, so the kernel does too. Normalised to sum
// `total`.
cv::Mat IntegrateTranslatingDisk(double radius,
                                 int half_size,
                                 int subsamples,
                                 double total) {
  const int side = 2 * half_size + 1;
  std::vector<double> weights(side * side, 0.0);
  const double dy = 1.0 / subsamples;
  // The profile is symmetric in y: integrate rows i >= 0 and mirror them, so
  // the kernel is exactly symmetric.
  ForEachChordPiece(radius,
                    half_size,
                    subsamples,
                    /*first_column=*/-half_size,
                    [&](int i, int j, double lo, double hi, double a) {
                      // Integral of (x + a) dx over [lo, hi].
                      weights[(i + half_size) * side + j + half_size] +=
                          (0.5 * (hi * hi - lo * lo) + a * (hi - lo)) * dy;
                    });
  MirrorRowsBelowCentre(half_size, &weights);
  double sum = 0;
  for (const double w : weights) {
    sum += w;
  }
  cv::Mat kernel(side, side, CV_32FC1);
  if (sum <= 0) {
    // Only reachable for a vanishing disk; the limit is a delta.
    kernel.setTo(0);
    kernel.at<float>(half_size, half_size) = static_cast<float>(total);
    return kernel;
  }
  for (int i = 0; i < side; ++i) {
    for (int j = 0; j < side; ++j) {
      kernel.at<float>(i, j) =
          static_cast<float>(weights[i * side + j] * total / sum);
    }
  }
  return kernel;
}

}  // namespace

TranslatingDiskPsf::TranslatingDiskPsf(int subsamples_per_pixel)
    : subsamples_per_pixel_(subsamples_per_pixel) {
  DPSFM_CHECK_GE(subsamples_per_pixel, 1)
      << "subsamples_per_pixel must be positive";
}

std::string TranslatingDiskPsf::Name() const {
  std::ostringstream name;
  name << "translating_disk(subsamples=" << subsamples_per_pixel_ << ")";
  return name.str();
}

double TranslatingDiskPsf::CentroidOffsetPerRadius() {
  return 3.0 * M_PI / 32.0;
}

int TranslatingDiskPsf::KernelRadius(double signed_radius_px) const {
  DPSFM_CHECK(std::isfinite(signed_radius_px))
      << "blur radius must be finite, got " << signed_radius_px;
  // Column j has weight iff j - 0.5 < R, i.e. j <= ceil(R + 0.5) - 1.
  const double radius = std::abs(signed_radius_px);
  return std::max(0, static_cast<int>(std::ceil(radius + 0.5)) - 1);
}

DPKernels TranslatingDiskPsf::Kernels(double signed_radius_px) const {
  const int half_size = KernelRadius(signed_radius_px);
  const double radius = std::abs(signed_radius_px);
  // Mass towards +x. Near (r < 0): that is the left view (cli contract).
  const cv::Mat towards_plus_x =
      IntegrateTranslatingDisk(radius, half_size, subsamples_per_pixel_, 0.5);
  cv::Mat towards_minus_x;
  cv::flip(towards_plus_x, towards_minus_x, 1);
  return AssignBySign(signed_radius_px, towards_plus_x, towards_minus_x);
}

bool SplitProfileParams::CheckCentroidOffsetRange(double min_centroid_offset,
                                                  double max_centroid_offset,
                                                  std::string* failure) {
  // Inside the family's range.
  DPSFM_CHECK_OPTION_VALUE(
      min_centroid_offset >=
          SplitProfileParams::MinCentroidOffset() * (1 - 1e-9),
      min_centroid_offset);
  DPSFM_CHECK_OPTION_VALUE(
      max_centroid_offset <=
          SplitProfileParams::MaxCentroidOffset() * (1 + 1e-9),
      max_centroid_offset);
  DPSFM_CHECK_OPTION_VALUE(min_centroid_offset < max_centroid_offset,
                           max_centroid_offset);
  return true;
}

bool SplitProfileParams::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(split_exponent) &&
                               split_exponent >= 0.05 && split_exponent <= 8,
                           split_exponent);
  DPSFM_CHECK_OPTION_VALUE(
      std::isfinite(crosstalk) && crosstalk >= 0 && crosstalk <= 0.45,
      crosstalk);
  DPSFM_CHECK_OPTION_VALUE(
      std::isfinite(rim_softness) && rim_softness >= 0 && rim_softness <= 0.5,
      rim_softness);
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(rim_brightness) &&
                               rim_brightness >= 0 && rim_brightness <= 4,
                           rim_brightness);
  return true;
}

std::string SplitProfileParams::ToString() const {
  std::ostringstream s;
  s << std::setprecision(4) << "split_exponent=" << split_exponent
    << ", crosstalk=" << crosstalk << ", rim_softness=" << rim_softness;
  if (rim_brightness > 0) s << ", rim_brightness=" << rim_brightness;
  return s.str();
}

SplitProfilePsf::SplitProfilePsf(const SplitProfileParams& params,
                                 int subsamples_per_pixel)
    : params_(params), subsamples_per_pixel_(subsamples_per_pixel) {
  DPSFM_CHECK(params.Check()) << "invalid split profile (" << params.ToString()
                              << "): " << OptionCheckFailure(params);
  DPSFM_CHECK_GE(subsamples_per_pixel, 1)
      << "subsamples_per_pixel must be positive";
}

std::string SplitProfilePsf::Name() const {
  std::ostringstream name;
  name << std::setprecision(6) << "split_profile(p=" << params_.split_exponent
       << ",c=" << params_.crosstalk << ",e=" << params_.rim_softness;
  if (params_.rim_brightness > 0) name << ",b=" << params_.rim_brightness;
  name << ",subsamples=" << subsamples_per_pixel_ << ")";
  return name.str();
}

int SplitProfilePsf::KernelRadius(double signed_radius_px) const {
  DPSFM_CHECK(std::isfinite(signed_radius_px))
      << "blur radius must be finite, got " << signed_radius_px;
  const double radius = std::abs(signed_radius_px);
  const int disk = std::max(0, static_cast<int>(std::ceil(radius + 0.5)) - 1);
  // The rim's Gaussian reaches 3 sigma further.
  return disk +
         static_cast<int>(std::ceil(3.0 * params_.rim_softness * radius));
}

DPKernels SplitProfilePsf::Kernels(double signed_radius_px) const {
  const int half = KernelRadius(signed_radius_px);
  const double radius = std::abs(signed_radius_px);
  const int side = 2 * half + 1;
  const double p = params_.split_exponent;
  // Antiderivatives of g(t) = sign(t) |t|^p and of t^2 g(t) (the bright
  // rim's x^2 term): |t|^(p + 1) / (p + 1) and |t|^(p + 3) / (p + 3), from
  // one pow. Neighbouring pieces of a chord share an end (hi of one is lo
  // of the next), so the last end's values are kept: one pow per piece
  // instead of four (the kernel grid of a profile fit renders hundreds of
  // kernels per candidate profile).
  struct Antiderivatives {
    double t = std::numeric_limits<double>::quiet_NaN();
    double g1 = 0, g3 = 0;
  };
  auto antiderivatives = [p](double t, Antiderivatives* at) {
    if (t == at->t) return;
    const double power = std::pow(std::abs(t), p + 1);
    at->t = t;
    at->g1 = power / (p + 1);
    at->g3 = power * t * t / (p + 3);
  };
  const double b = params_.rim_brightness;
  const double inv_r2 = radius > 0 ? 1 / (radius * radius) : 0;
  // Weight towards +x; the view leaning -x is its mirror image. The profile
  // is symmetric in y, and each view the other's mirror image in x: the
  // quadrant i, j >= 0 is integrated and mirrored.
  std::vector<double> plus(side * side, 0.0), minus(side * side, 0.0);
  const double dy = 1.0 / subsamples_per_pixel_;
  Antiderivatives at_lo, at_hi;
  ForEachChordPiece(
      radius,
      half,
      subsamples_per_pixel_,
      /*first_column=*/0,
      [&](int i, int j, double lo, double hi, double a) {
        // Exact along x, with the weight 1 + b (x^2 + y^2) /
        // R^2 (y^2 = R^2 - a^2): (1 / 2) integral of w (1 +-
        // g(x / a)) dx.
        const double w0 = 1 + b * (radius * radius - a * a) * inv_r2;
        const double w2 = b * inv_r2;
        const double base =
            0.5 * (w0 * (hi - lo) + w2 * (hi * hi * hi - lo * lo * lo) / 3) *
            dy;
        if (lo / a == at_hi.t) std::swap(at_lo, at_hi);
        antiderivatives(lo / a, &at_lo);
        antiderivatives(hi / a, &at_hi);
        const double split = 0.5 *
                             (w0 * a * (at_hi.g1 - at_lo.g1) +
                              w2 * a * a * a * (at_hi.g3 - at_lo.g3)) *
                             dy;
        plus[(i + half) * side + j + half] += base + split;
        minus[(i + half) * side + j + half] += base - split;
      });
  MirrorColumnsLeftOfCentre(half, &plus, &minus);
  MirrorRowsBelowCentre(half, &plus);
  MirrorRowsBelowCentre(half, &minus);
  cv::Mat towards_plus_x(side, side, CV_32FC1);
  cv::Mat towards_minus_x(side, side, CV_32FC1);
  double total = 0;
  for (int k = 0; k < side * side; ++k) total += plus[k] + minus[k];
  if (!(total > 0)) {
    // A vanishing disk: the limit is a delta in each view.
    towards_plus_x.setTo(0);
    towards_plus_x.at<float>(half, half) = 0.5f;
    towards_plus_x.copyTo(towards_minus_x);
  } else {
    const double c = params_.crosstalk;
    for (int k = 0; k < side * side; ++k) {
      towards_plus_x.at<float>(k / side, k % side) =
          static_cast<float>(((1 - c) * plus[k] + c * minus[k]) / total);
      towards_minus_x.at<float>(k / side, k % side) =
          static_cast<float>(((1 - c) * minus[k] + c * plus[k]) / total);
    }
  }
  const double sigma = params_.rim_softness * radius;
  if (sigma > 0.05) {
    cv::GaussianBlur(towards_plus_x,
                     towards_plus_x,
                     cv::Size(side, side),
                     sigma,
                     sigma,
                     cv::BORDER_CONSTANT);
    cv::GaussianBlur(towards_minus_x,
                     towards_minus_x,
                     cv::Size(side, side),
                     sigma,
                     sigma,
                     cv::BORDER_CONSTANT);
    // Keep half the energy each (the Gaussian's truncated tails).
    towards_plus_x *= 0.5 / cv::sum(towards_plus_x)[0];
    towards_minus_x *= 0.5 / cv::sum(towards_minus_x)[0];
  }
  return AssignBySign(signed_radius_px, towards_plus_x, towards_minus_x);
}

double SplitProfileParams::CentroidOffset() const {
  const double p = split_exponent, b = rim_brightness;
  const double numerator = 2.0 / (p + 2.0) * (4.0 / 3.0 + 4.0 * b / 15.0) +
                           32.0 * b / (15.0 * (p + 4.0));
  return numerator / (M_PI * (1.0 + 0.5 * b)) * (1.0 - 2.0 * crosstalk);
}

double SplitProfileParams::MinCentroidOffset() {
  SplitProfileParams params;
  params.crosstalk = 0.45;
  return params.CentroidOffset();
}

double SplitProfileParams::MaxCentroidOffset() {
  SplitProfileParams params;
  params.split_exponent = 0.05;
  params.rim_brightness = 4;
  return params.CentroidOffset();
}

SplitProfileParams SplitProfileParams::ForCentroidOffset(double kappa) {
  DPSFM_CHECK(kappa >= MinCentroidOffset() * (1 - 1e-9) &&
              kappa <= MaxCentroidOffset() * (1 + 1e-9))
      << "centroid offset " << kappa << " R outside the family's ["
      << MinCentroidOffset() << ", " << MaxCentroidOffset() << "]";
  SplitProfileParams params;
  const double linear = SplitProfileParams().CentroidOffset();
  SplitProfileParams sharpest;
  sharpest.split_exponent = 0.05;
  if (kappa > sharpest.CentroidOffset()) {
    // kappa pi (1 + b / 2) = A + B b, linear in b (CentroidOffset).
    const double p = sharpest.split_exponent;
    const double a = 8.0 / (3.0 * (p + 2.0));
    const double bb = 8.0 / (15.0 * (p + 2.0)) + 32.0 / (15.0 * (p + 4.0));
    params.split_exponent = p;
    params.rim_brightness = std::min(
        4.0, std::max(0.0, (a - kappa * M_PI) / (0.5 * kappa * M_PI - bb)));
  } else if (kappa >= linear) {
    params.split_exponent = std::max(0.05, 8.0 / (3.0 * M_PI * kappa) - 2.0);
  } else {
    params.crosstalk = std::min(0.45, 0.5 * (1.0 - kappa / linear));
  }
  return params;
}

int MagnifiedHalfSize(int half, double factor) {
  // The outermost input square ends at (half + 0.5) f; an output pixel j is
  // needed while j - 0.5 lies inside (1e-9: exact multiples stay outside).
  return std::max(
      0, static_cast<int>(std::ceil((half + 0.5) * factor - 0.5 - 1e-9)));
}

cv::Mat MagnifyKernel(const cv::Mat& kernel, double factor) {
  DPSFM_CHECK(kernel.type() == CV_32FC1 && kernel.rows == kernel.cols &&
              kernel.rows % 2 == 1)
      << "MagnifyKernel needs an odd square CV_32FC1 kernel";
  DPSFM_CHECK(factor >= 0 && std::isfinite(factor))
      << "magnification must be finite and non-negative, got " << factor;
  const int in_half = kernel.rows / 2;
  const int out_half = MagnifiedHalfSize(in_half, factor);
  const int in_side = kernel.rows, out_side = 2 * out_half + 1;
  // overlap(k, j): share of input column k's square [(k - 0.5) f,
  // (k + 0.5) f] lying in output column [j - 0.5, j + 0.5] (rows alike).
  cv::Mat weights = cv::Mat::zeros(out_side, in_side, CV_64FC1);
  for (int k = -in_half; k <= in_half; ++k) {
    const double lo = (k - 0.5) * factor, hi = (k + 0.5) * factor;
    if (hi - lo < 1e-12) {
      weights.at<double>(out_half, k + in_half) = 1;  // a point at the centre
      continue;
    }
    for (int j = -out_half; j <= out_half; ++j) {
      const double overlap = std::min(hi, j + 0.5) - std::max(lo, j - 0.5);
      if (overlap > 0) {
        weights.at<double>(j + out_half, k + in_half) = overlap / (hi - lo);
      }
    }
  }
  cv::Mat in64;
  kernel.convertTo(in64, CV_64FC1);
  const cv::Mat out64 = weights * in64 * weights.t();
  cv::Mat out;
  out64.convertTo(out, CV_32FC1);
  return out;
}

namespace {

cv::Mat CheckedReferenceKernel(const cv::Mat& kernel, const char* which) {
  DPSFM_CHECK(!kernel.empty() && kernel.channels() == 1 &&
              (kernel.depth() == CV_32F || kernel.depth() == CV_64F))
      << "the " << which << " measured kernel must be a float matrix";
  DPSFM_CHECK(kernel.rows == kernel.cols && kernel.rows % 2 == 1)
      << "the " << which << " measured kernel must be odd and square, got "
      << kernel.cols << "x" << kernel.rows;
  cv::Mat k;
  kernel.convertTo(k, CV_32FC1);
  double lo = 0, hi = 0;
  cv::minMaxLoc(k, &lo, &hi);
  DPSFM_CHECK(std::isfinite(lo) && std::isfinite(hi) && cv::checkRange(k))
      << "the " << which << " measured kernel has non-finite values";
  // Measured kernels carry small negative noise after background removal;
  // a PSF is non-negative, so it is clipped. Larger negative lobes mean the
  // array is not a PSF.
  DPSFM_CHECK(lo >= -0.05 * hi)
      << "the " << which << " measured kernel has negative values down to "
      << lo << " (max " << hi << "): not a PSF";
  cv::max(k, 0.0, k);
  const double sum = cv::sum(k)[0];
  DPSFM_CHECK(sum > 0) << "the " << which << " measured kernel sums to zero";
  k *= 0.5 / sum;
  return k;
}

std::string HashKernels(const cv::Mat& a, const cv::Mat& b) {
  // FNV-1a over the normalised kernels' bytes: Name() must tell profiles
  // apart (kernel caches are keyed by it).
  uint64_t h = 1469598103934665603ull;
  for (const cv::Mat* m : {&a, &b}) {
    const cv::Mat c = m->isContinuous() ? *m : m->clone();
    const unsigned char* p = c.ptr<unsigned char>();
    for (size_t i = 0; i < c.total() * c.elemSize(); ++i) {
      h = (h ^ p[i]) * 1099511628211ull;
    }
  }
  std::ostringstream s;
  s << std::hex << h;
  return s.str();
}

}  // namespace

MeasuredKernelPsf::MeasuredKernelPsf(const cv::Mat& left,
                                     const cv::Mat& right,
                                     double reference_radius_px,
                                     bool far_side)
    : left_(CheckedReferenceKernel(left, "left")),
      right_(CheckedReferenceKernel(right, "right")),
      reference_radius_px_(reference_radius_px),
      far_side_(far_side) {
  DPSFM_CHECK(left_.size() == right_.size())
      << "the left and right measured kernels differ in size (" << left_.cols
      << " vs " << right_.cols << ")";
  DPSFM_CHECK(reference_radius_px > 0.5 && std::isfinite(reference_radius_px))
      << "the reference radius must exceed 0.5 px, got " << reference_radius_px;
  // Convention: for a far point the left view leans towards -x.
  const double lx = KernelCentroid(left_).x, rx = KernelCentroid(right_).x;
  DPSFM_CHECK(far_side ? lx < rx : lx > rx)
      << "the measured " << (far_side ? "far" : "near")
      << "-side kernels have the left centroid at x = " << lx
      << " and the right one at " << rx << ": for a point "
      << (far_side ? "farther" : "nearer")
      << " than the focus the left kernel must lie "
      << (far_side ? "left" : "right")
      << " of the right one (swap the views, or the side)";
  std::ostringstream name;
  name << std::setprecision(6)
       << "measured_kernels(r_ref=" << reference_radius_px_
       << ",side=" << (far_side_ ? "far" : "near") << ",size=" << left_.cols
       << ",hash=" << HashKernels(left_, right_) << ")";
  name_ = name.str();
}

std::string MeasuredKernelPsf::Name() const { return name_; }

int MeasuredKernelPsf::KernelRadius(double signed_radius_px) const {
  DPSFM_CHECK(std::isfinite(signed_radius_px))
      << "blur radius must be finite, got " << signed_radius_px;
  return MagnifiedHalfSize(left_.rows / 2,
                           std::abs(signed_radius_px) / reference_radius_px_);
}

DPKernels MeasuredKernelPsf::Kernels(double signed_radius_px) const {
  DPSFM_CHECK(std::isfinite(signed_radius_px))
      << "blur radius must be finite, got " << signed_radius_px;
  const double factor = std::abs(signed_radius_px) / reference_radius_px_;
  DPKernels kernels;
  kernels.left = MagnifyKernel(left_, factor);
  kernels.right = MagnifyKernel(right_, factor);
  const bool far = signed_radius_px > 0;
  if (far != far_side_ && signed_radius_px != 0) {
    cv::flip(kernels.left, kernels.left, -1);
    cv::flip(kernels.right, kernels.right, -1);
  }
  return kernels;
}

DPPsfLayout DPPsfLayout::ColumnBands(int num_bands) {
  DPPsfLayout layout;
  layout.cols = num_bands;
  return layout;
}

bool DPPsfLayout::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_GE(rows, 1);
  DPSFM_CHECK_OPTION_GE(cols, 1);
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(x0) && x0 >= 0, x0);
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(y0) && y0 >= 0, y0);
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(x1) && x1 > x0 && x1 <= 1, x1);
  DPSFM_CHECK_OPTION_VALUE(std::isfinite(y1) && y1 > y0 && y1 <= 1, y1);
  return true;
}

int DPPsfLayout::CellAt(double x_fraction, double y_fraction) const {
  auto index = [](double f, double lo, double hi, int n) {
    const double t = (f - lo) / (hi - lo) * n;
    if (!(t > 0)) return 0;  // also NaN
    return std::min(n - 1, static_cast<int>(t));
  };
  return index(y_fraction, y0, y1, rows) * cols +
         index(x_fraction, x0, x1, cols);
}

std::string DPPsfLayout::ToString() const {
  std::ostringstream s;
  s << rows << "x" << cols << " grid";
  if (x0 != 0 || y0 != 0 || x1 != 1 || y1 != 1) {
    s << " over [" << x0 << ", " << x1 << "] x [" << y0 << ", " << y1 << "]";
  }
  return s.str();
}

DPPsfField DPPsfField::Uniform(std::shared_ptr<const DPPsfModel> psf) {
  DPPsfField field;
  field.cells.push_back(std::move(psf));
  return field;
}

const DPPsfModel& DPPsfField::At(double x_fraction, double y_fraction) const {
  return *cells[layout.CellAt(x_fraction, y_fraction)];
}

void DPPsfField::CheckValid() const {
  DPSFM_CHECK(layout.Check()) << "invalid DP PSF layout " << layout.ToString()
                              << ": " << OptionCheckFailure(layout);
  DPSFM_CHECK_EQ(static_cast<int>(cells.size()), layout.NumCells())
      << "the DP PSF layout " << layout.ToString() << " needs "
      << layout.NumCells() << " profiles, got " << cells.size();
  for (const auto& psf : cells) {
    DPSFM_CHECK(psf != nullptr) << "a DP PSF model is required";
  }
}

std::string DPPsfField::Name() const {
  if (cells.size() == 1) return cells[0]->Name();
  std::ostringstream name;
  name << layout.ToString() << ":";
  if (cells.size() <= 4) {
    for (const auto& psf : cells) name << " " << psf->Name();
  } else {
    name << " " << cells.front()->Name() << " ... " << cells.back()->Name()
         << " (" << cells.size() << " cells)";
  }
  return name.str();
}

double CentroidOffsetPerRadius(const DPPsfModel& psf, double radius_px) {
  DPSFM_CHECK(radius_px > 0 && std::isfinite(radius_px))
      << "radius must be positive, got " << radius_px;
  return CentroidOffsetPerRadius(psf.Kernels(radius_px), radius_px);
}

double CentroidOffsetPerRadius(const DPKernels& kernels, double radius_px) {
  return (KernelCentroid(kernels.right).x - KernelCentroid(kernels.left).x) /
         (2 * radius_px);
}

cv::Mat ConvolvePsf(const cv::Mat& image, const cv::Mat& psf) {
  DPSFM_CHECK(image.type() == CV_32FC1 || image.type() == CV_32FC3)
      << "ConvolvePsf needs a CV_32FC1 or CV_32FC3 image";
  DPSFM_CHECK(!image.empty()) << "ConvolvePsf needs a non-empty image";
  DPSFM_CHECK_EQ(psf.type(), CV_32FC1) << "the PSF must be CV_32FC1";
  DPSFM_CHECK(psf.rows % 2 == 1 && psf.cols % 2 == 1)
      << "the PSF must have odd sides, got " << psf.cols << "x" << psf.rows;
  // filter2D correlates; correlating with the point-reflected kernel about its
  // centre is convolution.
  cv::Mat flipped;
  cv::flip(psf, flipped, -1);
  cv::Mat result;
  cv::filter2D(
      image, result, -1, flipped, cv::Point(-1, -1), 0, cv::BORDER_REFLECT_101);
  return result;
}

cv::Point2d KernelCentroid(const cv::Mat& kernel) {
  DPSFM_CHECK(!kernel.empty() && kernel.type() == CV_32FC1)
      << "KernelCentroid needs a non-empty CV_32FC1 kernel";
  double sum = 0, sx = 0, sy = 0;
  const double cx = (kernel.cols - 1) / 2.0;
  const double cy = (kernel.rows - 1) / 2.0;
  for (int i = 0; i < kernel.rows; ++i) {
    for (int j = 0; j < kernel.cols; ++j) {
      const double w = kernel.at<float>(i, j);
      sum += w;
      sx += w * (j - cx);
      sy += w * (i - cy);
    }
  }
  DPSFM_CHECK(sum != 0) << "kernel sums to zero";
  return cv::Point2d(sx / sum, sy / sum);
}

}  // namespace dpsfm
