#include "dpsfm/core/blur/kernel_estimation.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <opencv2/imgproc.hpp>

#include "dpsfm/core/util/check.h"

namespace dpsfm {
namespace {

// The solve runs on the images' x and y derivatives: B = k * S implies
// dB = k * dS, derivatives carry no offset between the exposures, and they
// whiten the texture's spectrum (natural images are dominated by low
// frequencies, which leave the kernel's shape badly conditioned).
std::vector<cv::Mat> Derivatives(const cv::Mat& image) {
  cv::Mat f, dx, dy;
  image.convertTo(f, CV_64FC1);
  const cv::Mat kx = (cv::Mat_<double>(1, 2) << -1, 1);
  cv::filter2D(f, dx, CV_64F, kx, cv::Point(0, 0), 0, cv::BORDER_REPLICATE);
  cv::filter2D(f, dy, CV_64F, kx.t(), cv::Point(0, 0), 0, cv::BORDER_REPLICATE);
  return {dx, dy};
}

// The normal equations of min_k sum_x (B(x) - sum_d k(d) S(x - d))^2 over
// the region's interior Omega (x at least 2h from the border, so x - d stays
// inside for every |d| <= h; the derivatives' last row and column are left
// out). Unknowns are row-major over d = (dy, dx) in [-h, h]^2.
struct NormalEquations {
  Eigen::MatrixXd gram;
  Eigen::VectorXd rhs;
  double energy = 0;  // sum over Omega of B(x)^2
};

void AddNormalEquations(const cv::Mat& s,
                        const cv::Mat& b,
                        int h,
                        NormalEquations* eq) {
  const int k = 2 * h + 1;
  const cv::Rect omega(2 * h, 2 * h, s.cols - 4 * h - 1, s.rows - 4 * h - 1);
  // G(d1, d2) = sum_{x in Omega} S(x - d1) S(x - d2)
  //           = sum_{y in Omega - d1} P_v(y),  P_v(y) = S(y) S(y + v),
  // v = d1 - d2. One integral image of P_v per lag makes every entry exact
  // in four look-ups. S is zero-padded by 2h so that P_v exists over the
  // whole frame; the look-ups of valid pairs never touch the padding.
  cv::Mat padded;
  cv::copyMakeBorder(s,
                     padded,
                     2 * h,
                     2 * h,
                     2 * h,
                     2 * h,
                     cv::BORDER_CONSTANT,
                     cv::Scalar(0));
  const cv::Rect frame(2 * h, 2 * h, s.cols, s.rows);
  cv::Mat product, integral;
  for (int vy = -2 * h; vy <= 2 * h; ++vy) {
    for (int vx = -2 * h; vx <= 2 * h; ++vx) {
      cv::multiply(padded(frame), padded(frame + cv::Point(vx, vy)), product);
      cv::integral(product, integral, CV_64F);
      for (int dy1 = std::max(-h, vy - h); dy1 <= std::min(h, vy + h); ++dy1) {
        const int dy2 = dy1 - vy;
        const int y0 = omega.y - dy1, y1 = y0 + omega.height;
        for (int dx1 = std::max(-h, vx - h); dx1 <= std::min(h, vx + h);
             ++dx1) {
          const int dx2 = dx1 - vx;
          const int x0 = omega.x - dx1, x1 = x0 + omega.width;
          eq->gram((dy1 + h) * k + dx1 + h, (dy2 + h) * k + dx2 + h) +=
              integral.at<double>(y1, x1) - integral.at<double>(y0, x1) -
              integral.at<double>(y1, x0) + integral.at<double>(y0, x0);
        }
      }
    }
  }
  // c(d) = sum_{x in Omega} S(x - d) B(x).
  const cv::Mat b_omega = b(omega);
  for (int dy = -h; dy <= h; ++dy) {
    for (int dx = -h; dx <= h; ++dx) {
      eq->rhs((dy + h) * k + dx + h) +=
          s(omega - cv::Point(dx, dy)).dot(b_omega);
    }
  }
  eq->energy += b_omega.dot(b_omega);
}

NormalEquations BuildNormalEquations(const cv::Mat& sharp,
                                     const cv::Mat& blurred,
                                     int h) {
  const int n = (2 * h + 1) * (2 * h + 1);
  NormalEquations eq;
  eq.gram = Eigen::MatrixXd::Zero(n, n);
  eq.rhs = Eigen::VectorXd::Zero(n);
  const std::vector<cv::Mat> ds = Derivatives(sharp), db = Derivatives(blurred);
  for (size_t i = 0; i < ds.size(); ++i) {
    AddNormalEquations(ds[i], db[i], h, &eq);
  }
  return eq;
}

// D^T D for the forward differences of a k x k kernel (both axes).
Eigen::MatrixXd GradientPenalty(int k) {
  const int n = k * k;
  Eigen::MatrixXd penalty = Eigen::MatrixXd::Zero(n, n);
  auto add_pair = [&](int a, int b) {
    penalty(a, a) += 1;
    penalty(b, b) += 1;
    penalty(a, b) -= 1;
    penalty(b, a) -= 1;
  };
  for (int y = 0; y < k; ++y) {
    for (int x = 0; x < k; ++x) {
      if (x + 1 < k) add_pair(y * k + x, y * k + x + 1);
      if (y + 1 < k) add_pair(y * k + x, (y + 1) * k + x);
    }
  }
  return penalty;
}

// min 1/2 x^T H x - c^T x subject to x >= 0 (H positive definite), by the
// active-set method of Lawson and Hanson written on the normal equations:
// exact in finitely many steps however badly H is conditioned. Eigen 3.4
// has no NNLS, and a kernel has a few hundred unknowns, so each step is one
// small Cholesky solve on the free set.
Eigen::VectorXd SolveNonNegativeQuadratic(const Eigen::MatrixXd& hm,
                                          const Eigen::VectorXd& c,
                                          int max_iterations,
                                          int* iterations) {
  const int n = static_cast<int>(c.size());
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  std::vector<bool> free(n, false);
  const double tol = 1e-12 * std::max(c.cwiseAbs().maxCoeff(), 1e-300);
  auto solve_free = [&](Eigen::VectorXd* z) {
    std::vector<int> idx;
    for (int i = 0; i < n; ++i) {
      if (free[i]) idx.push_back(i);
    }
    const int m = static_cast<int>(idx.size());
    Eigen::MatrixXd a(m, m);
    Eigen::VectorXd rhs(m);
    for (int i = 0; i < m; ++i) {
      rhs(i) = c(idx[i]);
      for (int j = 0; j < m; ++j) a(i, j) = hm(idx[i], idx[j]);
    }
    const Eigen::VectorXd sol = a.llt().solve(rhs);
    z->setZero(n);
    for (int i = 0; i < m; ++i) (*z)(idx[i]) = sol(i);
  };
  int it = 0;
  for (; it < max_iterations; ++it) {
    const Eigen::VectorXd w = c - hm * x;  // minus the gradient
    int best = -1;
    for (int i = 0; i < n; ++i) {
      if (!free[i] && w(i) > tol && (best < 0 || w(i) > w(best))) best = i;
    }
    if (best < 0) break;  // KKT conditions hold
    free[best] = true;
    Eigen::VectorXd z;
    for (int inner = 0; inner <= n; ++inner) {
      solve_free(&z);
      double alpha = 1;
      for (int i = 0; i < n; ++i) {
        if (free[i] && z(i) <= 0) alpha = std::min(alpha, x(i) / (x(i) - z(i)));
      }
      if (alpha >= 1) break;
      x += alpha * (z - x);
      for (int i = 0; i < n; ++i) {
        if (free[i] && x(i) <= 1e-15 * std::max(1.0, x.maxCoeff())) {
          free[i] = false;
          x(i) = 0;
        }
      }
    }
    x = z;
  }
  *iterations = it;
  return x;
}

}  // namespace

bool KernelEstimationOptions::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_VALUE(half_size >= 1 && half_size <= 24, half_size);
  DPSFM_CHECK_OPTION_VALUE(smoothness >= 0 && std::isfinite(smoothness),
                           smoothness);
  DPSFM_CHECK_OPTION_GE(max_iterations, 1);
  return true;
}

EstimatedKernel EstimateKernel(const cv::Mat& sharp,
                               const cv::Mat& blurred,
                               const KernelEstimationOptions& options) {
  DPSFM_CHECK_OPTIONS(options, "KernelEstimationOptions");
  const int h = options.half_size, k = 2 * h + 1;
  DPSFM_CHECK(sharp.size() == blurred.size() && sharp.channels() == 1 &&
              blurred.channels() == 1)
      << "the sharp and blurred images must be grey and of equal size";
  DPSFM_CHECK(sharp.cols > 4 * h + 8 && sharp.rows > 4 * h + 8)
      << "a " << sharp.cols << "x" << sharp.rows
      << " region is too small to measure a kernel of half-size " << h;
  const NormalEquations eq = BuildNormalEquations(sharp, blurred, h);
  const double mean_diagonal = eq.gram.diagonal().mean();
  DPSFM_CHECK(mean_diagonal > 0 && std::isfinite(mean_diagonal))
      << "the sharp image has no texture to measure a kernel against";
  const Eigen::MatrixXd system =
      eq.gram + options.smoothness * mean_diagonal * GradientPenalty(k);
  EstimatedKernel out;
  const Eigen::VectorXd x = SolveNonNegativeQuadratic(
      system, eq.rhs, options.max_iterations, &out.iterations);
  // ||B - k * S||^2 = ||B||^2 - 2 c^T k + k^T G k.
  const double residual =
      std::max(0.0, eq.energy - 2 * eq.rhs.dot(x) + x.dot(eq.gram * x));
  out.relative_residual = eq.energy > 0 ? std::sqrt(residual / eq.energy) : 1;
  out.kernel.create(k, k, CV_32FC1);
  for (int i = 0; i < k * k; ++i) {
    out.kernel.at<float>(i / k, i % k) = static_cast<float>(x(i));
  }
  return out;
}

cv::Mat ShiftKernel(const cv::Mat& kernel, double dx, double dy) {
  DPSFM_CHECK(std::isfinite(dx) && std::isfinite(dy));
  cv::Mat in;
  kernel.convertTo(in, CV_32FC1);
  const double sum = cv::sum(in)[0];
  // out(x) = in(x - d): warpAffine samples the source at M^-1 x.
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, dx, 0, 1, dy);
  cv::Mat out;
  cv::warpAffine(in,
                 out,
                 shift,
                 in.size(),
                 cv::INTER_LINEAR,
                 cv::BORDER_CONSTANT,
                 cv::Scalar(0));
  const double kept = cv::sum(out)[0];
  if (kept > 0 && sum > 0) out *= sum / kept;
  return out;
}

EstimatedDPKernels EstimateDPKernels(const cv::Mat& sharp,
                                     const cv::Mat& left,
                                     const cv::Mat& right,
                                     const KernelEstimationOptions& options) {
  DPSFM_CHECK(left.size() == sharp.size() && right.size() == sharp.size())
      << "the DP views and the sharp image differ in size";
  cv::Mat s, l, r;
  sharp.convertTo(s, CV_32FC1);
  left.convertTo(l, CV_32FC1);
  right.convertTo(r, CV_32FC1);
  const double sharp_mean = cv::mean(s)[0];
  const double total_mean = cv::mean(l)[0] + cv::mean(r)[0];
  DPSFM_CHECK(sharp_mean > 0 && total_mean > 0)
      << "the sharp image or the DP views carry no light";
  s *= total_mean / sharp_mean;
  const EstimatedKernel el = EstimateKernel(s, l, options);
  const EstimatedKernel er = EstimateKernel(s, r, options);
  const double wl = cv::sum(el.kernel)[0], wr = cv::sum(er.kernel)[0];
  DPSFM_CHECK(wl > 0 && wr > 0)
      << "no kernel explains the blurred views (left " << wl << ", right " << wr
      << "): is the sharp capture of the same scene?";
  EstimatedDPKernels out;
  out.left_share = wl / (wl + wr);
  out.light_ratio = wl + wr;
  out.relative_residual = std::max(el.relative_residual, er.relative_residual);
  const cv::Mat sum = el.kernel / wl + er.kernel / wr;
  const cv::Point2d centre = KernelCentroid(sum);
  out.recentred_by = centre;
  out.kernels.left = ShiftKernel(el.kernel / (2 * wl), -centre.x, -centre.y);
  out.kernels.right = ShiftKernel(er.kernel / (2 * wr), -centre.x, -centre.y);
  return out;
}

}  // namespace dpsfm
