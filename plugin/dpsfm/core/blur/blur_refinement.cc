#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "dpsfm/core/blur/blur_search_internal.h"
#include "dpsfm/core/util/lanes.h"

namespace dpsfm {
namespace internal {
namespace {

// Sum over `rect` of (image * kernel) (true convolution), from the integral
// image of `image`: sum_d kernel(d) * (sum of image over rect - d). Every
// shifted rect must lie inside the image.
double BlurredSum(const cv::Mat& integral,
                  const cv::Mat& kernel,
                  const cv::Rect& rect) {
  const int cy = kernel.rows / 2;
  const int cx = kernel.cols / 2;
  double total = 0;
  for (int i = 0; i < kernel.rows; ++i) {
    const float* k = kernel.ptr<float>(i);
    const int y0 = rect.y - (i - cy);
    const int y1 = y0 + rect.height;
    const double* top = integral.ptr<double>(y0);
    const double* bottom = integral.ptr<double>(y1);
    for (int j = 0; j < kernel.cols; ++j) {
      if (k[j] == 0) continue;
      const int x0 = rect.x - (j - cx);
      const int x1 = x0 + rect.width;
      total += k[j] * (bottom[x1] - bottom[x0] - top[x1] + top[x0]);
    }
  }
  return total;
}

double Dot(const std::vector<float>& a, const std::vector<float>& b) {
  return DotInLanes(a.data(), b.data(), a.size());
}

}  // namespace

BlurRefinement::BlurRefinement(const BlurTables& t,
                               const cv::Mat& gl,
                               const cv::Mat& gr,
                               double offset,
                               double sigma2_hp,
                               const cv::Mat& integral_left,
                               const cv::Mat& integral_right)
    : t_(t),
      options_(t.options),
      gl_(gl),
      gr_(gr),
      given_integral_left_(integral_left),
      given_integral_right_(integral_right),
      offset_(offset),
      sigma2_hp_(sigma2_hp),
      inv_m_(1.0 / t.num_interior),
      spectra_(t.grid->NumSpectrumClasses()),
      evals_(t.num_nodes) {}

void BlurRefinement::MakePositiveViews() {
  if (!left_positive_.empty()) return;
  left_positive_ = gl_ + offset_;
  right_positive_ = gr_ + offset_;
}

cv::Mat BlurRefinement::PositiveIntegral(const cv::Mat& view, double offset) {
  // The same arithmetic as MakePositiveViews, so that a given integral is
  // the one EqualiseGain would take, to the bit.
  const cv::Mat positive = view + offset;
  cv::Mat integral;
  cv::integral(positive, integral, CV_64F);
  return integral;
}

void BlurRefinement::Evaluate(int n) {
  NodeEval& e = evals_[n];
  if (e.done) return;
  const DPKernelGrid& grid = *t_.grid;
  const int c = grid.SpectrumClassOf(n);
  const ViewSpectra& views = TransformedViews(c);
  SpectraProductDifference(views.left,
                           grid.RightSpectrum(n),
                           views.right,
                           grid.LeftSpectrum(n),
                           &product_);
  const cv::Mat interior =
      grid.InteriorOfInverse(c, &product_, &residual_image_);
  e.residual.resize(t_.num_interior);
  float* out = e.residual.data();
  for (int y = 0; y < interior.rows; ++y) {
    const float* row = interior.ptr<float>(y);
    std::copy(row, row + interior.cols, out);
    out += interior.cols;
  }
  e.energy = Dot(e.residual, e.residual);
  e.done = true;
  if (n > 0 && evals_[n - 1].done) {
    evals_[n - 1].next_dot = Dot(evals_[n - 1].residual, e.residual);
  }
  if (n + 1 < t_.num_nodes && evals_[n + 1].done) {
    e.next_dot = Dot(e.residual, evals_[n + 1].residual);
  }
}

double BlurRefinement::CurrentSigma2() const {
  if (!options_.subtract_noise_floor) return 0.0;
  double s2 = sigma2_hp_;
  for (int n = 0; n < t_.num_nodes; ++n) {
    if (evals_[n].done) s2 = std::min(s2, RawLoss(n) / t_.noise_gain[n]);
  }
  return s2;
}

BlurRefinement::Minimum BlurRefinement::Minimise(int lo,
                                                 int hi,
                                                 double sigma2) const {
  Minimum best;
  best.lo = lo;
  best.hi = hi;
  auto consider = [&](double radius, double corrected, double raw) {
    const double tol = 1e-9 * std::abs(raw) + 1e-300;
    if (corrected < best.corrected - tol ||
        (corrected <= best.corrected + tol &&
         std::abs(radius) < std::abs(best.radius))) {
      best.radius = radius;
      best.corrected = corrected;
      best.raw = raw;
    }
  };
  for (int n = lo; n <= hi; ++n) {
    consider(t_.Radius(n), RawLoss(n) - sigma2 * t_.noise_gain[n], RawLoss(n));
  }
  for (int n = lo; n < hi; ++n) {
    // L(t) = alpha (1-t)^2 + 2 beta t (1-t) + gamma t^2 (raw and noise
    // floor are both quadratic forms in the interpolated kernels).
    const double ra = RawLoss(n);
    const double rb = evals_[n].next_dot * inv_m_;
    const double rc = RawLoss(n + 1);
    const double alpha = ra - sigma2 * t_.noise_gain[n];
    const double beta = rb - sigma2 * t_.noise_cross[n];
    const double gamma = rc - sigma2 * t_.noise_gain[n + 1];
    const double curvature = alpha - 2 * beta + gamma;
    if (curvature <= 0) continue;  // minimum at an end node
    const double s = (alpha - beta) / curvature;
    if (s <= 0 || s >= 1) continue;
    const double corrected =
        alpha * (1 - s) * (1 - s) + 2 * beta * s * (1 - s) + gamma * s * s;
    const double raw =
        ra * (1 - s) * (1 - s) + 2 * rb * s * (1 - s) + rc * s * s;
    consider(t_.Radius(n) + s * t_.step, corrected, raw);
  }
  return best;
}

BlurRefinement::Minimum BlurRefinement::Refine(int start) {
  int lo = std::max(0, start - 1);
  int hi = std::min(t_.num_nodes - 1, start + 1);
  for (int n = lo; n <= hi; ++n) Evaluate(n);
  int budget = options_.max_refinement_evaluations - (hi - lo + 1);
  while (true) {
    const double sigma2 = CurrentSigma2();
    const Minimum m = Minimise(lo, hi, sigma2);
    // Extend while an end node is (tied for) the minimum: the loss may
    // still fall beyond it, or a plateau (in-focus deltas) may continue.
    const double tol = 1e-9 * std::abs(m.raw);
    const bool at_lo =
        RawLoss(lo) - sigma2 * t_.noise_gain[lo] <= m.corrected + tol;
    const bool at_hi =
        RawLoss(hi) - sigma2 * t_.noise_gain[hi] <= m.corrected + tol;
    if (at_lo && lo > 0 && budget > 0) {
      Evaluate(--lo);
      --budget;
    } else if (at_hi && hi < t_.num_nodes - 1 && budget > 0) {
      Evaluate(++hi);
      --budget;
    } else {
      return m;
    }
  }
}

int BlurRefinement::NearestNode(double radius) const {
  return std::max(
      0,
      std::min(t_.num_nodes - 1,
               static_cast<int>(std::round(radius / t_.step)) + t_.half_nodes));
}

void BlurRefinement::EqualiseGain(double radius) {
  cv::Mat integral_left, integral_right;
  if (!gains_moved_ && !given_integral_left_.empty()) {
    integral_left = given_integral_left_;
    integral_right = given_integral_right_;
  } else {
    MakePositiveViews();
    cv::integral(left_positive_, integral_left, CV_64F);
    cv::integral(right_positive_, integral_right, CV_64F);
  }
  // Interior sums are linear in the kernels: interpolate like them.
  const double pos = std::max(
      0.0, std::min(t_.num_nodes - 1.0, radius / t_.step + t_.half_nodes));
  const int n0 = std::min(t_.num_nodes - 2, static_cast<int>(pos));
  const double s = pos - n0;
  double a = 0, b = 0;
  for (const int n : {n0, n0 + 1}) {
    const double w = n == n0 ? 1 - s : s;
    a += w * BlurredSum(integral_left, t_.grid->RightKernel(n), t_.interior);
    b += w * BlurredSum(integral_right, t_.grid->LeftKernel(n), t_.interior);
  }
  if (!(a > 0 && b > 0) || std::abs(a / b - 1) < 1e-7) return;
  const double half_log_ratio = 0.5 * std::log(a / b);
  MakePositiveViews();
  left_positive_ *= std::exp(-half_log_ratio);
  right_positive_ *= std::exp(half_log_ratio);
  gains_moved_ = true;
  // Into new matrices: gl_ and gr_ may share the caller's (a prepared
  // patch searched with many profiles, from several threads).
  cv::Mat gl, gr;
  left_positive_.convertTo(gl, CV_32FC1, 1.0, -offset_);
  right_positive_.convertTo(gr, CV_32FC1, 1.0, -offset_);
  gl_ = gl;
  gr_ = gr;
  for (ViewSpectra& views : spectra_) views.fresh = false;
}

const BlurRefinement::ViewSpectra& BlurRefinement::TransformedViews(int c) {
  ViewSpectra& views = spectra_[c];
  if (!views.fresh) {
    views.left = t_.grid->TransformInput(gl_, t_.border, c);
    views.right = t_.grid->TransformInput(gr_, t_.border, c);
    views.fresh = true;
  }
  return views;
}

}  // namespace internal
}  // namespace dpsfm
